#pragma once
// Simulated electro-optical detection system of the odometry/INS/vision method (seeds/004 §III):
// bearings from the vehicle's body x axis to known landmarks, CCW positive, wrapped to
// (-pi, pi], with white Gaussian noise and the instrument's angular resolution (quantization).
// No middleware, no clock: fed ground truth, with its own seeded generator, so the driver
// process (lcmloc-vision) and the experiment (lcmloc-landmark-experiment) produce the same numbers.
#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "lcmloc/core/landmark_fix.hpp"

namespace lcmloc::sim {

struct TruthState;

constexpr double kArcSec = 3.14159265358979323846 / 180.0 / 3600.0;  ///< one arc second [rad]

/// A landmark of the map: id and position in the local frame (x east, y north) [m].
struct Landmark {
  int id = 0;
  double x = 0.0, y = 0.0;
};

struct VisionSensorConfig {
  double rate_hz = 1.0;                 ///< observation rate [Hz] (<= ground-truth rate)
  double bearing_std = 30.0 * kArcSec;  ///< white noise, 1 sigma [rad] (§III: 30")
  double resolution = 14.0 * kArcSec;   ///< angular resolution (quantization step) [rad]; 0 = none (§III: 14")
  uint64_t seed = 0;                    ///< noise seed; 0 = derived from scenario.seed
  double max_range = 0.0;               ///< landmarks farther than this are not seen [m]; 0 = no limit
};

/// One observation: ids and bearings of the landmarks in view, in map order.
struct VisionSample {
  int64_t utime = 0;
  std::vector<int> ids;
  std::vector<double> bearings;  ///< [rad] from the body x axis, CCW positive, (-pi, pi]
  double bearing_std = 0.0;      ///< 1 sigma of noise and quantization together [rad]
};

/// Throws std::invalid_argument naming the entry for a duplicate id or a non-finite position.
void validateLandmarks(const std::vector<Landmark>& landmarks);

/// The map as the landmark fix takes it (id -> position).
std::map<int, Eigen::Vector2d> landmarkMap(const std::vector<Landmark>& landmarks);

/// The bearings in the landmark fix's convention (core::landmark: clockwise from the body axis,
/// i.e. alpha = -bearing), in the sample's order.
std::vector<core::landmark::Bearing> toFixBearings(const VisionSample& s);
/// Heading CCW from east (this project's frames) <-> heading clockwise from north (the fix's
/// psi, the paper's eq. 9-13); the map is its own inverse.
double toFixHeading(double heading);

class VisionSensor {
 public:
  /// Throws std::invalid_argument for a bad rate, noise, resolution, range or landmark map.
  VisionSensor(const VisionSensorConfig& cfg, std::vector<Landmark> landmarks, uint64_t seed);

  /// Fed every ground-truth sample; emits an observation at rate_hz (the first at the first
  /// sample). Landmarks out of range are left out; an observation with none is still emitted.
  /// A truth sample with a non-finite position or heading gives nothing (and starts no clock).
  std::optional<VisionSample> sample(const TruthState& truth);

  /// One observation now from pose (x, y, heading CCW from east), drawing fresh noise.
  VisionSample observe(double x, double y, double heading, int64_t utime = 0);

  /// Noise-free bearing of landmark (lx, ly) from pose (x, y, heading), (-pi, pi].
  static double trueBearing(double x, double y, double heading, double lx, double ly);
  /// Rounds angle a to the nearest multiple of step (step <= 0: unchanged) and wraps it.
  static double quantize(double a, double step);
  /// 1 sigma of the measured bearing: sqrt(std^2 + resolution^2 / 12).
  static double effectiveStd(const VisionSensorConfig& cfg);

  const std::vector<Landmark>& landmarks() const { return landmarks_; }
  const VisionSensorConfig& config() const { return cfg_; }

 private:
  VisionSensorConfig cfg_;
  std::vector<Landmark> landmarks_;
  std::mt19937_64 rng_;
  bool started_ = false;
  int64_t next_utime_ = 0;
};

}  // namespace lcmloc::sim
