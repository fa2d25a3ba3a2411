#pragma once
// Plain data types of the fusion core. No middleware: these are what the LCM adapter
// converts lcmtypes to and from (lib/bus/include/lcmloc/bus/convert.hpp).
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace lcmloc::core {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;

/// Vehicle pose of the rear-axle centre M in the world frame: x [m], y [m], theta [rad].
using Pose = Eigen::Vector3d;

/// One odometry increment over (previous utime, utime].
struct OdometryInput {
  int64_t utime = 0;
  double delta_s = 0.0;       ///< distance increment of M [m]
  double steering = 0.0;      ///< measured steering angle psi [rad] (valid if has_steering)
  bool has_steering = false;  ///< car-like source: delta_theta follows eq. 2 from steering
  double delta_theta = 0.0;   ///< heading increment [rad] (used as is when !has_steering)
  /// No NaN or Inf in a field the filters read (the engine skips the input otherwise).
  bool finite() const { return std::isfinite(delta_s) && std::isfinite(steering) && std::isfinite(delta_theta); }
};

/// A magnetic-ruler marker detection.
struct RulerDetection {
  int64_t utime = 0;
  double lateral_offset = 0.0;  ///< d_m, body y (left) positive [m]
  double quality = 1.0;         ///< [0, 1]
  std::string sensor = "MAGRULER";  ///< input channel (for gate decisions)
  int64_t seq = 0;                  ///< seq of the measurement on its channel
};

/// One inertial sample (body frame: x forward, y left, z up). Consumed by the GNSS filters
/// (tvekf, ukf_gps): accel[0] is the forward acceleration of §2.1, mag gives the heading of §2.2.
struct ImuInput {
  int64_t utime = 0;
  Vec3 accel = Vec3::Zero();  ///< specific force [m/s^2]
  Vec3 gyro = Vec3::Zero();   ///< angular rate [rad/s]
  Vec3 mag = Vec3::Zero();    ///< magnetic field [gauss]
  std::string sensor = "IMU"; ///< input channel (for gate decisions)
  int64_t seq = 0;
  bool finite() const { return accel.allFinite() && gyro.allFinite() && mag.allFinite(); }
};

/// A GNSS fix already converted to the local metric frame (x east, y north) by the adapter.
struct GpsInput {
  int64_t utime = 0;
  bool has_fix = true;         ///< false: the receiver reported no fix (x, y meaningless)
  double x = 0.0, y = 0.0;     ///< [m]
  double position_std = 0.0;   ///< 1-sigma horizontal error [m]; <= 0 or NaN: use the filter's default
  std::string sensor = "GPS";
  int64_t seq = 0;
  /// A fix without a fix carries no position: it is handed on (the filter reports "no_fix").
  bool finite() const { return !has_fix || (std::isfinite(x) && std::isfinite(y)); }
};

/// A range-bearing observation of a map landmark (channel LANDMARKS), measured from the
/// reference point M in the body frame (x forward, y left).
struct LandmarkObservation {
  int64_t utime = 0;
  int landmark_id = -1;         ///< id in the map; -1 = unknown (nearest neighbour, gated)
  double range = 0.0;           ///< distance from M to the landmark [m]
  double bearing = 0.0;         ///< angle from the body x axis to the landmark, CCW [rad]
  double range_std = 0.0;       ///< 1 sigma [m]; <= 0: the filter's landmark.range_std
  double bearing_std = 0.0;     ///< 1 sigma [rad]; <= 0: the filter's landmark.bearing_std
  std::string sensor = "LANDMARKS";
  int64_t seq = 0;
  bool finite() const {
    return std::isfinite(range) && std::isfinite(bearing) && std::isfinite(range_std) && std::isfinite(bearing_std);
  }
};

/// A range-only measurement to a beacon of the map (channel BEACONS), from M.
struct BeaconRange {
  int64_t utime = 0;
  int beacon_id = 0;            ///< id in the map
  double range = 0.0;           ///< [m]
  double range_std = 0.0;       ///< 1 sigma [m]; <= 0: the filter's landmark.beacon_std
  std::string sensor = "BEACONS";
  int64_t seq = 0;
  bool finite() const { return std::isfinite(range) && std::isfinite(range_std); }
};

/// A magnetic marker of the map.
struct Marker {
  int id = 0;
  double x = 0.0;  ///< [m]
  double y = 0.0;  ///< [m]
};
using MarkerMap = std::vector<Marker>;

/// Filter status, same numbering as pose_t.STATUS_*.
enum class FilterStatus : int32_t { Ok = 0, DeadReckoning = 1, Lockout = 2, Uninitialized = 3 };

/// State handed from one filter to the next (hot swap) and published as the pose.
/// The first three entries of x are always (x, y, theta); further entries are named in names.
struct FilterState {
  int64_t utime = 0;
  Eigen::VectorXd x;               ///< size n >= 3
  Eigen::MatrixXd P;               ///< n x n
  std::vector<std::string> names;  ///< size n, e.g. {"x","y","theta","odo_scale","steer_bias"}
  FilterStatus status = FilterStatus::Ok;
};

/// Outcome of one absolute measurement in a filter.
struct GateDecision {
  int64_t utime = 0;
  std::string sensor;
  int64_t measurement_seq = 0;
  Eigen::VectorXd innovation;  ///< z - z_hat, angles wrapped (empty when no candidate)
  double mahalanobis = 0.0;    ///< v' S^-1 v (0 when no candidate)
  double gate = 0.0;           ///< threshold in force (+inf when ungated)
  bool accepted = false;
  int marker_id = -1;
  std::string reason;          ///< "accepted", "ungated", "gate", "no_candidate", "bad_input"
};

/// Bearings to known landmarks (channel VISION), as landmark_bearings_t: each bearing is the
/// angle from the body x (forward) axis to the landmark, CCW positive [rad].
struct BearingsInput {
  int64_t utime = 0;
  int64_t seq = 0;
  std::string sensor = "VISION";
  std::vector<int> ids;
  std::vector<double> bearings;
  double bearing_std = 0.0;  ///< 1-sigma [rad]; <= 0 or NaN: the engine's default
};

/// An absolute pose (x, y, theta) with its covariance, e.g. from a three-landmark fix, used to
/// re-initialize a filter (Filter::applyFix).
struct PoseFix {
  int64_t utime = 0;
  Vec3 pose = Vec3::Zero();
  Mat3 cov = Mat3::Identity();
  std::string source;  ///< what produced it (for decisions and events)
};

}  // namespace lcmloc::core
