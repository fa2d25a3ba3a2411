#pragma once
// Simulated IMU and GPS receiver of the GPS + IMU + encoder method (seeds/002). No middleware,
// no clock: stepped with ground truth and their own seeded generators, so the driver processes
// (lcmloc-imu, lcmloc-gps) and the in-process scenario runner produce the same numbers.
// Configuration structs with defaults; YAML loading lives in common/config.
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lcmloc/core/types.hpp"

namespace lcmloc::sim {

struct TruthState;

struct ImuSensorConfig {
  bool enabled = false;            ///< fed to the filters by the in-process scenario runner
  double rate_hz = 100.0;          ///< [Hz] (<= ground-truth rate)
  double gravity = 9.81;           ///< [m/s^2]
  double accel_std = 0.05;         ///< white noise, 1 sigma per axis [m/s^2]
  double accel_bias = 0.02;        ///< constant bias per axis, drawn N(0, this) once [m/s^2]
  double accel_bias_rw = 0.001;    ///< drifting bias: random walk [m/s^2/sqrt(s)]
  double accel_range = 39.24;      ///< saturation (clipping) per axis [m/s^2] (4 g)
  double gyro_std = 0.002;         ///< [rad/s]
  double gyro_bias = 0.002;        ///< [rad/s]
  double gyro_bias_rw = 1e-5;      ///< [rad/s/sqrt(s)]
  double gyro_range = 8.73;        ///< [rad/s] (500 deg/s)
  double mag_horizontal = 0.2;     ///< horizontal Earth field [gauss]
  double mag_vertical = -0.4;      ///< vertical Earth field, up positive [gauss]
  double declination = 0.0;        ///< magnetic north east of true north [rad]
  double mag_std = 0.002;          ///< white noise per axis [gauss]
  double mag_disturbance_std = 0.005;  ///< slowly varying disturbance per axis (first-order Markov) [gauss]
  double mag_disturbance_tau = 10.0;   ///< its correlation time [s]
};

struct GpsOutage {
  double start = 0.0;      ///< [s] after the first ground-truth sample
  double duration = 0.0;   ///< [s]: the receiver reports "no fix" meanwhile
};
struct GpsJump {
  double at = 0.0;         ///< [s] after the first ground-truth sample
  double duration = 0.0;   ///< [s]: fixes in [at, at + duration] are offset by (dx, dy)
  double dx = 0.0, dy = 0.0;  ///< [m]
};

struct GpsSensorConfig {
  bool enabled = false;            ///< fed to the filters by the in-process scenario runner
  double rate_hz = 1.0;            ///< [Hz]
  std::string error_model = "uniform";  ///< "uniform": each axis in [-error, error]; "gaussian": 1 sigma = error
  double error = 5.0;              ///< [m] (the paper: random error of +-5 m)
  double reported_std = 0.0;       ///< position_std the fixes carry [m]; 0 = the model's own 1 sigma
  int satellites = 8;
  double hdop = 1.0;
  std::vector<GpsOutage> outages;
  std::vector<GpsJump> jumps;
};

/// One IMU sample (body frame x forward, y left, z up; level vehicle).
struct ImuSample {
  int64_t utime = 0;
  core::Vec3 accel, gyro, mag;
  /// The engine's input of this sample, as received on `sensor` with this seq.
  core::ImuInput input(const std::string& sensor, int64_t seq) const { return {utime, accel, gyro, mag, sensor, seq}; }
};

class ImuSensor {
 public:
  ImuSensor(const ImuSensorConfig& cfg, double wheelbase, uint64_t seed);
  /// Fed every ground-truth sample; emits a sample at rate_hz (the first truth sample only
  /// starts the clock: the forward acceleration is a difference of speeds).
  std::optional<ImuSample> sample(const TruthState& truth);
  /// Noise-free sample of a level car-like vehicle (forward acceleration a, speed v, steering
  /// psi, heading theta): accel (a, v^2 tan(psi) / L, g), gyro (0, 0, v tan(psi) / L), mag the
  /// Earth field in the body.
  static ImuSample ideal(const ImuSensorConfig& cfg, double wheelbase, double a, double v,
                         double psi, double theta);
 private:
  ImuSensorConfig cfg_;
  double wheelbase_;
  std::mt19937_64 rng_;
  bool started_ = false;
  int64_t next_utime_ = 0, last_utime_ = 0;
  double last_speed_ = 0.0;
  core::Vec3 accel_bias_, gyro_bias_, mag_dist_;
};

/// One GNSS fix in the local frame (x east, y north).
struct GpsFixSample {
  int64_t utime = 0;
  bool has_fix = true;
  double x = 0.0, y = 0.0;
  double position_std = 0.0;  ///< [m]
  int satellites = 0;
  double hdop = 0.0;
};

class GpsSensor {
 public:
  /// Throws std::invalid_argument for a bad error model or rate.
  GpsSensor(const GpsSensorConfig& cfg, uint64_t seed);
  /// Fed every ground-truth sample; emits a fix (or a no-fix report during an outage) at rate_hz.
  std::optional<GpsFixSample> sample(const TruthState& truth);
  /// 1 sigma per axis of the error model [m].
  double modelStd() const;
 private:
  GpsSensorConfig cfg_;
  std::mt19937_64 rng_;
  bool started_ = false;
  int64_t t0_ = 0, next_utime_ = 0;
};

}  // namespace lcmloc::sim
