#pragma once
// The simulated world: reference path, marker map, vehicle and sensor models. No middleware,
// no clock: each model is stepped with message times and its own seeded generator, so a
// process wrapping it and the in-process scenario runner produce the same numbers.
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lcmloc/core/types.hpp"
#include "lcmloc/sim/scenario_config.hpp"

namespace lcmloc::sim {

/// Reference path as a function of arc length.
class Path {
 public:
  explicit Path(const PathConfig& cfg);
  double length() const;
  core::Pose poseAt(double s) const;   ///< position and tangent heading at arc length s
  double curvatureAt(double s) const;
  /// Arc length of the point of the path closest to (x, y), searched near hint.
  double project(double x, double y, double hint) const;
 private:
  PathConfig cfg_;
  std::vector<double> seg_start_;   // arc length at segment starts
  std::vector<core::Pose> seg_pose_;
};

/// Marker map of the scenario: layout.count markers along the path (ids 0..count-1).
core::MarkerMap makeMarkerMap(const Path& path, const MarkerLayout& layout);

/// True vehicle state.
struct TruthState {
  int64_t utime = 0;
  double x = 0, y = 0, heading = 0, speed = 0, steering = 0, distance = 0;
};

/// Car-like vehicle (eq. 1-2) following the path with a pure-pursuit steering law and a small
/// lateral weave; accelerates to cruise speed and stops end_margin past the path's last marker.
class VehicleSim {
 public:
  VehicleSim(const VehicleConfig& cfg, const Path& path, double stop_at_arc, uint64_t seed);
  const TruthState& state() const;
  /// Advances one publication period (1/rate_hz); returns the new state.
  const TruthState& step();
  bool finished() const;  ///< stopped at the end of the run
 private:
  VehicleConfig cfg_;
  const Path* path_;
  double stop_at_arc_;
  TruthState st_;
  double arc_hint_ = 0.0;
  bool finished_ = false;
  std::mt19937_64 rng_;
};

/// Drive and steering encoders. Fed every ground-truth sample; emits an increment at rate_hz.
struct OdometrySample {
  core::OdometryInput input;  ///< delta_s, steering, has_steering = true, delta_theta (eq. 2)
  int64_t ticks = 0;
};
class OdometrySensor {
 public:
  OdometrySensor(const OdometrySensorConfig& cfg, double wheelbase, uint64_t seed);
  /// A sample whose distance the encoder cannot count (not finite, or beyond 2^53 ticks) is
  /// skipped and leaves the state as it was (only the noise generator moved on): the next valid
  /// sample gives the right increment. Drivers refuse such ground truth before (TruthDriver).
  std::optional<OdometrySample> sample(const TruthState& truth);
 private:
  OdometrySensorConfig cfg_;
  double wheelbase_;
  std::mt19937_64 rng_;
  bool started_ = false;
  int64_t next_utime_ = 0;
  double last_true_distance_ = 0.0;
  double measured_distance_ = 0.0;  // accumulated measured distance (continuous)
  int64_t ticks_total_ = 0;
};

/// Vertical component [gauss] of the field of a vertical magnetic dipole of moment [A m^2]
/// (pointing up), at horizontal distance rho [m] and height dz [m] above the dipole:
/// Bz = mu0/(4 pi) m (3 cos^2(phi) - 1) / r^3, cos(phi) = dz / r (1 T = 1e4 gauss).
double dipoleVerticalField(double moment, double rho, double dz);

/// Noise-free readings [gauss] of the ruler's sensors with a single marker at `along` [m]
/// ahead of the ruler line and `lateral` [m] left of the ruler centre (body frame), Earth field
/// included. The one dipole profile used by the ruler's calibration and the fault injector.
std::vector<double> singleMarkerReadings(const MagRulerConfig& cfg, double along, double lateral);

/// Physical magnetic ruler: 13 AMR sensors reading the vertical field of dipole markers plus the
/// Earth's field and disturbances; peak mapping recovers d_m.
struct RulerReading {
  int64_t utime = 0;
  std::vector<double> readings;  ///< [gauss]
  bool detected = false;
  double lateral_offset = 0.0;   ///< [m]
  double quality = 0.0;
};
class MagneticRuler {
 public:
  MagneticRuler(const MagRulerConfig& cfg, const core::MarkerMap& markers, uint64_t seed);
  /// Noise-free vertical field [gauss] at a point (x, y, sensor height) of the world frame,
  /// Earth field included.
  double fieldAt(double x, double y) const;
  /// Raw readings of the 13 sensors for the vehicle at this true pose (noise included).
  std::vector<double> read(const TruthState& truth);
  /// Peak mapping: lateral offset d_m [m] from one set of readings; nullopt if no peak.
  std::optional<double> peakMap(const std::vector<double>& readings, double* quality = nullptr) const;
  /// Fed every ground-truth sample: returns a reading to publish (a detection as the ruler
  /// passes a marker, or a raw reading at publish_rate_hz), else nullopt.
  std::optional<RulerReading> sample(const TruthState& truth);
  double sensorLateral(int i) const;  ///< body-y position of sensor i [m]
 private:
  MagRulerConfig cfg_;
  core::MarkerMap markers_;
  std::mt19937_64 rng_;
  // detection state: along-track peak tracking, disturbance process, calibration table
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

/// Fault-marker injector: emits the configured faulty detections as the truth reaches them.
struct InjectedFault {
  RulerReading reading;
  FaultConfig fault;
  TruthState truth;
};
class FaultInjector {
 public:
  FaultInjector(std::vector<FaultConfig> faults, const MagRulerConfig& ruler, uint64_t seed);
  std::optional<InjectedFault> sample(const TruthState& truth);
 private:
  std::vector<FaultConfig> faults_;
  MagRulerConfig ruler_;
  std::size_t next_ = 0;
  std::mt19937_64 rng_;
  std::shared_ptr<const MagneticRuler> mapper_;  // peak mapping of the synthesised readings
};

}  // namespace lcmloc::sim
