#pragma once
// Simulation of §II of Wang & Wang (seeds/004): a ground vehicle trajectory on the WGS-84
// ellipsoid (start 40 N, 116 E, 0 m), an IMU of the paper's grade (gyro drift 0.1 deg/h
// first-order Markov 1800 s + 0.03 deg/h white; accelerometer bias 1e-4 g Markov 800 s + 1e-4 g
// white) and an odometer with scale error 0.005 + first-order Markov (3600 s) + 0.0003 white.
// No middleware, no clock: the driver process (lcmloc-ins-sim) and the in-process experiment
// (lcmloc-ins-experiment) step the same object and get the same numbers for the same seed.
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lcmloc/core/ins.hpp"
#include "lcmloc/core/types.hpp"
#include "lcmloc/sim/gnss_sensors.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::sim {

namespace ins = core::ins;

/// One piece of the motion profile: forward acceleration and yaw rate held for a duration.
struct InsMotionSegment {
  double duration = 1.0;  ///< [s]
  double accel = 0.0;     ///< forward acceleration [m/s^2] (the speed is clamped at 0)
  double yaw_rate = 0.0;  ///< CCW positive [deg/s]
};

struct InsSimConfig {
  uint64_t seed = 1;
  double rate_hz = 100.0;          ///< truth and IMU rate [Hz]
  int odometry_divider = 1;        ///< one odometry increment every this many IMU samples
  double duration = 3600.0;        ///< [s]; the profile is cut (or ends standing) there
  /// "paper": §II, 3600 s, about 65 km with starting, speeding, turning (the start below);
  /// "custom": the segments list.
  std::string profile = "paper";
  /// Start of the paper profile (all reach 12 m/s, cruise until 102 s, then the same run):
  /// "hard" (3 m/s^2 for 4 s, an early 10 deg/s turn, one hard stop-and-go), "gentle" (0.2 m/s^2
  /// from rest to 12 m/s), "gentle_turn" (the same with a 15 deg/s S-turn at 2-8 s),
  /// "gentle_stopgo" (two 0.5 m/s^2 stop-and-go pulses, then 0.5 m/s^2), "steady" (1 m/s^2).
  std::string start = "hard";
  std::vector<InsMotionSegment> segments;  ///< "custom" profile
  double latitude = 40.0, longitude = 116.0, height = 0.0;  ///< start [deg, deg, m]
  double heading = 1.5707963267948966;  ///< start heading theta, CCW from east [rad]
  // IMU grade (1 sigma; white noise given as the std of a 1 s average).
  double gyro_markov = 0.1;        ///< [deg/h]
  double gyro_tau = 1800.0;        ///< [s]
  double gyro_white = 0.03;        ///< [deg/h]
  double accel_markov = 1e-4;      ///< [g] (x and y axes)
  double accel_tau = 800.0;        ///< [s]
  double accel_white = 1e-4;       ///< [g]
  // Odometer: K = scale_error + Markov(scale_markov, scale_tau) + white; delta_s = (1 + K) true.
  double scale_error = 0.005;      ///< constant part (the paper's 0.005)
  double scale_markov = 0.001;     ///< Markov part 1 sigma (starts at 0)
  double scale_tau = 3600.0;       ///< [s]
  double scale_white = 0.0003;     ///< per increment
  /// IMU dropouts (no samples published) [start, start + duration) in seconds from the start.
  std::vector<std::pair<double, double>> imu_dropouts;
};

/// Whether start names a start of the paper profile.
bool insStartValid(const std::string& start);
/// The §II motion profile (or the custom one) as segments.
std::vector<InsMotionSegment> insProfile(const InsSimConfig& cfg);

/// One simulation step (1 / rate_hz).
struct InsSimStep {
  TruthState truth;                 ///< local ENU from the start (x east, y north), theta CCW from east
  ins::InsState truth_nav;          ///< geodetic truth
  std::optional<ImuSample> imu;     ///< body frame x forward, y left, z up (absent in a dropout)
  std::optional<OdometrySample> odometry;  ///< delta_s over the last odometry interval
  double scale_error = 0.0;         ///< true K of the odometer at this step
};

class InsSim {
 public:
  /// Throws std::invalid_argument for a bad configuration (message names the parameter).
  explicit InsSim(const InsSimConfig& cfg, int64_t start_utime = 0);
  /// The initial state (utime = start, at rest).
  InsSimStep initial() const;
  InsSimStep step();
  bool finished() const { return k_ >= n_steps_; }
  double time() const { return k_ / cfg_.rate_hz; }
  /// Local ENU metres of a geodetic position (origin: the start; radii at the start latitude).
  core::Vec2 toLocal(double lat, double lon) const;

 private:
  InsSimConfig cfg_;
  std::vector<InsMotionSegment> segs_;
  int64_t start_utime_ = 0;
  int64_t k_ = 0, n_steps_ = 0;
  double dt_ = 0.01;
  std::size_t seg_ = 0;
  double seg_t_ = 0.0;
  ins::Ins truth_;
  double speed_ = 0.0, distance_ = 0.0, odo_distance_true_ = 0.0;
  double lat0_ = 0, lon0_ = 0, sx_ = 1, sy_ = 1;
  std::mt19937_64 rng_imu_, rng_odo_;
  std::normal_distribution<double> n01_;
  ins::Vec3 gyro_bias_ = ins::Vec3::Zero(), accel_bias_ = ins::Vec3::Zero();
  double scale_markov_ = 0.0;
};

}  // namespace lcmloc::sim
