#pragma once
// Configuration of the simulated world and sensors (plain structs with defaults; YAML loading
// lives in common/config). Defaults are the paper's experiment (magnetic-ruler paper §4).
#include <cstdint>
#include <string>
#include <vector>

#include "lcmloc/core/types.hpp"
#include "lcmloc/sim/gnss_sensors.hpp"
#include "lcmloc/sim/vision_sensor.hpp"

namespace lcmloc::sim {

/// Reference path: starts at (x0, y0) heading theta0 and is a sequence of segments, each a
/// length [m] and a constant curvature [1/m] (0 = straight).
struct PathSegment {
  double length = 10.0;
  double curvature = 0.0;
};
struct PathConfig {
  double x0 = 0.0, y0 = 0.0, theta0 = 1.5707963267948966;
  std::vector<PathSegment> segments{{12.0, 0.0}, {14.0, 0.06}, {16.0, 0.0}};
};

/// Markers along the path: count markers every spacing metres of arc length from first_at.
struct MarkerLayout {
  int count = 20;
  double spacing = 2.0;   ///< [m]
  double first_at = 2.0;  ///< arc length of the first marker [m]
};

/// The same stretch of road (first marker to last, or less by under one spacing) with markers
/// `spacing` metres apart (> 0).
MarkerLayout respaced(const MarkerLayout& layout, double spacing);

struct VehicleConfig {
  double wheelbase = 2.5;           ///< L [m]
  double speed = 1.5;               ///< cruise speed [m/s]
  double accel = 0.5;               ///< acceleration / braking [m/s^2]
  double max_steering = 0.6;        ///< [rad]
  double lookahead = 3.0;           ///< path-follower look-ahead [m]
  double weave_amplitude = 0.08;    ///< lateral weave about the path [m] (makes d_m informative)
  double weave_wavelength = 11.0;   ///< [m]
  double rate_hz = 100.0;           ///< ground-truth publication rate [Hz]
  int substeps = 10;                ///< integration substeps per published sample
  double end_margin = 2.0;          ///< drive this far past the last marker, then stop [m]
  int64_t start_utime = 1000000;    ///< message time of the first sample [us]
};

struct OdometrySensorConfig {
  double rate_hz = 100.0;           ///< publication rate [Hz] (<= ground-truth rate)
  double tick_length = 0.001;       ///< drive-encoder resolution [m/tick]
  double scale_error = 0.01;        ///< per-run odometer scale error k: measured = (1+k) true
  double slip_std = 0.002;          ///< slip noise per metre travelled [m/sqrt(m)]
  double steering_bias = 0.008727;  ///< steering-encoder bias [rad] (0.5 deg)
  double steering_std = 0.002;      ///< steering-encoder noise [rad]
  double steering_resolution = 0.0005; ///< steering-encoder quantization [rad]
};

struct MagRulerConfig {
  int num_sensors = 13;
  double length = 1.0;              ///< [m]
  double height = 0.18;             ///< sensor height above the road [m]
  double marker_depth = 0.0125;     ///< dipole centre below the road surface [m]
  double ruler_offset = 1.5;        ///< L1: ruler ahead of M [m]
  double dipole_moment = 5.0;       ///< NdFeB marker moment [A m^2] (25 mm x 25 mm cylinder ~ 12 cm^3 at ~1e6 A/m -> ~10; 5 leaves margin)
  double earth_field_z = -0.45;     ///< vertical Earth field [gauss]
  double noise_std = 0.0005;        ///< sensor noise [gauss] (AMR resolution 85 ugauss + disturbances)
  double disturbance_std = 0.002;   ///< slowly varying common-mode disturbance [gauss]
  double gain_std = 0.02;           ///< per-sensor sensitivity mismatch (fixed per ruler) [-]
  double disturbance_tau = 5.0;     ///< correlation time of that disturbance (first-order Markov) [s]
  double detection_threshold = 0.05;  ///< peak above the tracked background to declare a marker [gauss]
  double publish_rate_hz = 0.0;     ///< raw (non-detection) readings rate; 0 = detections only
};

/// A fault-marker injection: when the vehicle's true travelled distance reaches at_distance,
/// publish a detection that is wrong.
struct FaultConfig {
  std::string kind = "phantom_marker";  ///< "phantom_marker" (a magnet not in the map) or "wrong_offset"
  double at_distance = 0.0;             ///< true distance travelled when injected [m]
  double lateral_offset = 0.0;          ///< d_m the fault reports [m]
};

struct ScenarioConfig {
  std::string name = "paper";
  uint64_t seed = 1;                ///< master seed: each component derives its own
  double realtime_factor = 1.0;     ///< 1.0 = live pace; larger = faster than real time
  PathConfig path;
  MarkerLayout markers;
  VehicleConfig vehicle;
  OdometrySensorConfig odometry;
  MagRulerConfig magruler;
  ImuSensorConfig imu;              ///< GPS + IMU method (seeds/002)
  GpsSensorConfig gps;
  std::vector<FaultConfig> faults{{"phantom_marker", 12.9, 0.10}, {"wrong_offset", 24.5, 0.35}};
  VisionSensorConfig vision;        ///< bearings to landmarks (seeds/004 §III)
  std::vector<Landmark> landmarks;  ///< landmark map (top-level `landmarks` key), ids unique
};

/// Arc length at which the vehicle stops: end_margin past the last marker, or the end of the
/// path when there are no markers (the GPS scenarios).
double stopArcLength(const ScenarioConfig& sc, double path_length);

/// Derives the seed of a named component from the master seed (deterministic, stable).
uint64_t componentSeed(uint64_t master, const std::string& component);

}  // namespace lcmloc::sim
