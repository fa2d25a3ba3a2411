#pragma once
// The filter interface of the fusion core. A filter is a value you can build in a unit test
// and feed numbers; the daemon, the offline replay and the scenario runner all drive filters
// through this interface only.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/core/map_index.hpp"
#include "lcmloc/core/types.hpp"
#include "lcmloc/core/ukf.hpp"

namespace lcmloc::core {

/// How the gate threshold is given. The paper's 6.635 is the 99% point of chi^2 with ONE degree
/// of freedom, while the range-bearing innovation has TWO (99%: 9.210). Default: probability
/// 0.99 on the innovation's true dimension (2), i.e. 9.210.
struct GateConfig {
  bool enabled = true;
  std::optional<double> value;   ///< explicit threshold (e.g. 6.635, the paper's); wins if set
  double probability = 0.99;     ///< used when value is not set
  int dof = 0;                   ///< 0: the innovation dimension; else use this dof (1 = paper)
  double threshold(int innovation_dim) const;  ///< the sigma of eq. 19 in force
};

/// Parameters of the GNSS filters (tvekf, ukf_gps): GPS + IMU + encoder + steering, the
/// time-varying EKF of Choi and Kong (seeds/002) and a UKF over the same sensors.
/// See docs/tvekf.md for the derivations.
struct GnssConfig {
  double accel_std = 0.1;          ///< forward accelerometer noise, 1 sigma [m/s^2]
  double accel_saturation = 0.0;   ///< |accel x| >= this is a saturated sample, not used [m/s^2]; 0 = no check
  double accel_unknown_std = 3.0;  ///< acceleration 1 sigma when no valid IMU sample arrived [m/s^2]
  double encoder_std = 0.02;       ///< encoder travelled-distance measurement, 1 sigma [m]
  double steering_std = 0.01;      ///< steering potentiometer, 1 sigma [rad]
  double heading_rw = 0.01;        ///< heading process noise [rad/sqrt(s)]
  double position_rw = 0.1;        ///< position process noise [m/sqrt(s)]
  double mag_std = 0.05;           ///< magnetometer heading, 1 sigma [rad]
  double declination = 0.0;        ///< magnetic declination, east positive [rad]
  bool use_magnetometer = true;    ///< fuse the magnetometer heading (§2.2)
  double gps_std = 2.9;            ///< GPS 1 sigma per axis when the fix carries none [m]
  double speed_std0 = 0.5;         ///< initial 1 sigma of the speed [m/s]
  /// Lock-out of the GPS gate: this many consecutive GPS gate rejections declare a lock-out
  /// (status LOCKOUT) until a fix is accepted or the filter re-localizes from refused fixes that
  /// agree (docs/tvekf.md "Re-localization"); nothing is inflated.
  int gps_lockout_rejections = 5;
  /// Lock-out of the magnetometer heading gate (samples): the heading covariance is inflated by
  /// FilterConfig::lockout_inflation (heading sigma up to 1 rad), again after every further
  /// mag_lockout_rejections rejections, until a heading is accepted.
  int mag_lockout_rejections = 50;
  double coast_timeout = 3.0;      ///< no accepted fix for this long: status DEAD_RECKONING [s]
  /// tvekf only: GPS-course heading aid for a vehicle without magnetometer (the heading of
  /// §2.2 is otherwise corrected by nothing but the magnetometer): between accepted fixes at
  /// least this much travel apart, chord direction of the fixes minus that of the dead-reckoned
  /// path is fused as a heading measurement [m]; 0 = off (the paper).
  double course_distance = 0.0;
  double course_std = 0.02;        ///< extra 1 sigma of a course measurement [rad]
};

/// Parameters of the odometry/INS filters ("odo_ins", "odo_ins_uncal"; Wang & Wang §II; see
/// docs/ins_experiment.md). Sensor grade defaults: §II of the paper.
struct InsFilterConfig {
  double latitude = 40.0;          ///< start (and local-frame origin) [deg]
  double longitude = 116.0;        ///< [deg]
  double height = 0.0;             ///< [m]
  Vec3 init_att_std{0.5, 0.5, 3.0};  ///< initial attitude error 1 sigma (E, N, U) [arcmin]
  double init_vel_std = 0.01;      ///< [m/s]
  double init_pos_std = 0.1;       ///< [m]
  double meas_vel_std = 0.01;      ///< odometer velocity measurement noise [m/s]
  double gyro_markov = 0.1;        ///< gyro drift, first-order Markov 1 sigma [deg/h]
  double gyro_tau = 1800.0;        ///< [s]
  double gyro_white = 0.03;        ///< [deg/h] (std of a 1 s average)
  double accel_markov = 1e-4;      ///< accelerometer bias, first-order Markov 1 sigma [g]
  double accel_tau = 800.0;        ///< [s]
  double accel_white = 1e-4;       ///< [g] (std of a 1 s average)
  double odo_scale = 0.005;        ///< odometer scale error 1 sigma (constant part, initial)
  double odo_markov = 0.005;       ///< Markov part 1 sigma (its process noise)
  double odo_tau = 3600.0;         ///< [s]
  double odo_white = 0.0003;       ///< white scale noise
  bool attitude_term = true;       ///< heading coupling of the odometer velocity in H
  bool paper_exact_h = false;      ///< the paper's printed H (no dKr column, no heading term)
  double max_imu_gap = 0.1;        ///< IMU interval beyond this is a dropout: coast, report [s]
  double max_coast = 5.0;          ///< dropout bridged this long by holding the last sample; beyond: attitude and velocity held [s]
};

/// Lock-out inflation stops at this heading 1-sigma [rad]: the UKFs' sigma points stay within
/// +-pi of the mean (sqrt(n + lambda) sigma < pi for every filter here).
constexpr double kLockoutMaxHeadingStd = 1.0;

/// Parameters shared by every filter of the magnetic-ruler family (defaults: the paper, §4,
/// as read in docs/paper_000_reading.md).
struct FilterConfig {
  std::string type = "ukf_gated";  ///< "dead_reckoning", "ukf", "ukf_gated", "ukf_calib", "tvekf", "ukf_gps", "ukf_landmarks"
  double wheelbase = 2.5;          ///< L [m]
  double ruler_offset = 1.5;       ///< L1: ruler centre ahead of M [m]
  double ruler_half_width = 0.5;   ///< half length of the ruler [m]
  Vec3 initial_pose{0.0, 0.0, 1.5707963267948966};
  Vec3 p0_diag{1e-2, 1e-2, 1e-2};  ///< P0 (paper §4)
  /// Pw (paper §4: diag(1e-4, 1e-4, 8.73e-3)) read as the process noise accumulated over one
  /// marker interval of travel: Q_step = Pw * |ds| / pw_distance. Set pw_distance = 0 to apply
  /// Pw per odometry step as printed (unusable at realistic odometry rates).
  Vec3 pw_diag{1e-4, 1e-4, 8.73e-3};
  double pw_distance = 2.0;        ///< [m] distance over which Pw accumulates
  Vec2 pv_diag{1e-4, 3.1e-4};      ///< Pv (paper §4): range [m^2], bearing [rad^2]
  SigmaParams sigma{1.0, 0.0, 0.0};  ///< paper: kappa = 0 (n + kappa = 3 for n = 3)
  GateConfig gate;                 ///< ignored by "ukf" (ungated) and "dead_reckoning"
  /// Association candidates: markers whose predicted body-frame position lies within
  /// |forward - L1| <= reach_forward + m and |left| <= ruler_half_width + reach_lateral + m,
  /// m = 3 sigma of the ruler position (position and L1 x heading uncertainty).
  double reach_forward = 0.5;      ///< [m]
  double reach_lateral = 0.2;      ///< [m]
  /// Lock-out: this many consecutive rejections (gate or no candidate) declare a lock-out
  /// (status LOCKOUT); the filter then inflates its covariance by lockout_inflation (each state
  /// up to its cap, see lockout_max_std), again after every further lockout_rejections
  /// rejections, until a marker is accepted (re-acquired).
  /// 0 disables detection.
  int lockout_rejections = 3;
  double lockout_inflation = 25.0;
  /// Lock-out inflation stops at this position 1-sigma [m] (every filter with a lock-out); the
  /// heading stops at kLockoutMaxHeadingStd and ukf_calib's scale and steering bias at their
  /// initial sigmas. Without a bound, a long run of rejections (a stretch of road whose markers
  /// are not in the map, a GPS far off for minutes) drove the covariance to infinity: the UKF's
  /// mean was lost in rounding, then the filter refused every input.
  double lockout_max_std = 100.0;
  /// "ukf_calib" only: odometer scale error k (delta_s_true = (1 + k) delta_s) and steering
  /// bias b (psi_true = psi - b) as extra states, each a random walk.
  double scale_std0 = 0.02;        ///< initial 1-sigma of k [-]
  double steer_bias_std0 = 0.02;   ///< initial 1-sigma of b [rad]
  double scale_rw = 1e-4;          ///< random walk of k per metre travelled [1/sqrt(m)]
  double steer_bias_rw = 1e-4;     ///< random walk of b per metre travelled [rad/sqrt(m)]
  /// "tvekf" and "ukf_gps" only (they also use wheelbase, initial_pose, p0_diag, sigma, gate and,
  /// for the magnetometer's lock-out, lockout_inflation).
  GnssConfig gnss;
  /// Heading process noise per radian turned [rad^2/rad], added to every odometry step of the
  /// magnetic-ruler family (dead_reckoning, ukf, ukf_gated, ukf_calib) and ukf_landmarks:
  /// Q_theta += pw_turn |delta_theta|. Without it a robot turning in place (delta_s = 0) would
  /// predict with zero process noise (Pw scales with |delta_s| only).
  double pw_turn = 1e-4;
  /// "ukf_landmarks" only: default measurement noise when an observation carries none.
  struct Landmarks {
    double range_std = 0.1;       ///< landmark range, 1 sigma [m]
    double bearing_std = 0.02;    ///< landmark bearing, 1 sigma [rad]
    double beacon_std = 0.1;      ///< beacon range, 1 sigma [m]
    /// Landmark observations whose errors are correlated from one observation to the next (a
    /// map error, a range error that depends on the distance): each update weighs the
    /// observation as (range, bearing) variance x this (the observations per independent one),
    /// while the gate still tests it against the variance itself. 1: independent.
    double correlation_factor = 1.0;
  } landmarks;
  /// Self-calibration states appended to a filter's state, each switched on here (all off by
  /// default: the filter is then the one without them). Each starts at its prior mean (0 unless
  /// given) with its prior 1-sigma and follows a random walk (the magnetometer bias: a
  /// first-order Markov process). See docs/config.md "Self-calibration".
  /// "ukf_landmarks":
  ///   odometer scale k:   delta_s_true = (1 + k) delta_s
  ///   yaw-rate scale g, bias b:  delta_theta_true = (1 + g) delta_theta - b dt
  ///   beacon range bias c: range = distance + c (one shared, or one per map entry)
  /// "tvekf" and "ukf_gps" (docs/tvekf.md "Self-calibration"):
  ///   odometer scale k:   the same (the encoder's distance and speed times 1 + k)
  ///   steering bias s:    steering_true = steering - s
  ///   magnetometer heading bias m:  heading_mag = theta + m
  struct Calibration {
    enum class BeaconBias { Off, Shared, PerBeacon };
    static constexpr int kMaxPerBeacon = 8;  ///< PerBeacon: at most this many map entries
    BeaconBias beacon_bias = BeaconBias::Off;
    double beacon_bias_mean = 0.0;    ///< prior mean of c (every beacon's) [m]
    double beacon_bias_std = 0.5;     ///< prior 1 sigma of c [m]
    double beacon_bias_rw = 1e-3;     ///< random walk of c [m/sqrt(s)]
    bool odo_scale = false;
    double odo_scale_mean = 0.0;      ///< prior mean of k [-]
    double odo_scale_std = 0.05;      ///< prior 1 sigma of k [-]
    double odo_scale_rw = 1e-4;       ///< random walk of k per metre travelled [1/sqrt(m)]
    bool yaw_rate_scale = false;
    double yaw_rate_scale_mean = 0.0; ///< prior mean of g [-]
    double yaw_rate_scale_std = 0.1;  ///< prior 1 sigma of g [-]
    double yaw_rate_scale_rw = 1e-4;  ///< random walk of g per radian turned [1/sqrt(rad)]
    bool yaw_rate_bias = false;
    double yaw_rate_bias_mean = 0.0;  ///< prior mean of b [rad/s]
    double yaw_rate_bias_std = 0.01;  ///< prior 1 sigma of b [rad/s]
    double yaw_rate_bias_rw = 1e-4;   ///< random walk of b [rad/s/sqrt(s)]
    bool steering_bias = false;       ///< GNSS filters only (ukf_landmarks refuses it)
    double steering_bias_mean = 0.0;  ///< prior mean of s [rad]
    double steering_bias_std = 0.01;  ///< prior 1 sigma of s [rad]
    double steering_bias_rw = 1e-5;   ///< random walk of s [rad/sqrt(s)]
    bool mag_bias = false;            ///< GNSS filters only (ukf_landmarks refuses it)
    double mag_bias_std = 0.025;      ///< steady 1 sigma of m (Markov) [rad]
    double mag_bias_tau = 10.0;       ///< correlation time of m [s]
    bool accel_bias = false;          ///< GNSS filters only: the forward accelerometer's bias b_a
    double accel_bias_std = 0.02;     ///< prior 1 sigma of b_a (mean 0) [m/s^2]
    double accel_bias_rw = 1e-3;      ///< random walk of b_a [m/s^2/sqrt(s)]
    bool any() const {
      return beacon_bias != BeaconBias::Off || odo_scale || yaw_rate_scale || yaw_rate_bias || steering_bias ||
             mag_bias || accel_bias;
    }
  } calibration;
  /// "odo_ins" and "odo_ins_uncal" only (they also use initial_pose for the start heading).
  InsFilterConfig ins;
};

/// A filter re-localized from the evidence of measurements its gate had refused (GNSS filters:
/// GPS fixes that agree with each other, carried forward by the dead-reckoned motion between
/// them, and all disagree with the estimate). The engine reports it (event "relocalized").
struct Relocalization {
  int64_t utime = 0;        ///< the newest fix, whose position was taken
  int fixes = 0;            ///< fixes that agreed (the newest included)
  int64_t first_utime = 0;  ///< the oldest of them
  double spread = 0;        ///< largest distance of an agreeing fix, carried forward, from the newest [m]
  double jump = 0;          ///< distance the position moved [m]
  bool heading_from_chord = false;  ///< heading from the chord of the fixes; else kept, its sigma opened
  double heading_change = 0;        ///< [rad] (0 when kept)
  double heading_std = 0;           ///< 1 sigma of the heading after it [rad]
  /// The evidence were observations of landmarks ("ukf_landmarks"; fixes counts them, landmarks
  /// the distinct landmarks among them, spread is the largest distance of one from its
  /// landmark, pose and heading from all of them); else GPS fixes.
  bool from_landmarks = false;
  int landmarks = 0;
};

/// Measurement kinds a filter may use (Filter::uses).
enum class Measurement { Ruler, Imu, Gps, Landmark, Beacon };

/// Odometry no increment covers (EngineConfig::odometry_gap): two consecutive inputs of one
/// odometry channel further apart than the limit whose seq does not follow (messages lost in
/// transit, a restarted sender). An increment carries the motion since its sender's previous
/// message, so the motion of the lost ones is lost with them. See docs/odometry_gap.md.
struct OdometryGap {
  int64_t from_utime = 0;      ///< the last odometry input before the gap
  int64_t to_utime = 0;        ///< where the next increment's own period begins (next_utime - period)
  int64_t next_utime = 0;      ///< the first odometry input after the gap
  double seconds = 0.0;        ///< to_utime - from_utime: the time no increment covers [s]
  double speed = 0.0;          ///< speed before the gap (recent increments) [m/s]
  bool has_steering = false;   ///< car-like source: the heading follows eq. 2 from steering
  double steering = 0.0;       ///< last steering angle [rad] (has_steering)
  double yaw_rate = 0.0;       ///< heading rate before the gap (recent increments) [rad/s]
  double accel_std = 0.5;      ///< 1 sigma of the speed change rate over the gap [m/s^2]
  double yaw_rate_std = 0.05;  ///< 1 sigma of the change of the yaw rate over the gap [rad/s]
  double max_position_std = 100.0;  ///< the bridge's position sigma stops here (FilterConfig::lockout_max_std) [m]
};
/// [s] The bridge moves the pose at the speed before the gap for at most this long: a vehicle
/// unseen for longer may have stopped or turned anywhere (its covariance still grows, up to
/// OdometryGap::max_position_std and kLockoutMaxHeadingStd).
inline constexpr double kMaxBridgeSeconds = 10.0;

/// The constant-velocity bridge of a gap: one increment over gap.seconds (at most
/// kMaxBridgeSeconds) at the speed and yaw rate (or steering) before it, stamped gap.to_utime.
OdometryInput bridgeIncrement(const OdometryGap& gap);
/// Pose covariance (x, y, theta) of what the bridge does not know, at heading theta: along the
/// track accel_std g^2 / 2 (a speed change), across it speed yaw_rate_std g^2 / 2 and on the
/// heading yaw_rate_std g (a yaw-rate change), these two fully correlated.
Mat3 bridgeNoise(const OdometryGap& gap, double theta);
/// [m] 1 sigma of a state's position along its larger axis (sqrt of the larger eigenvalue of
/// the (x, y) covariance).
double positionSigma(const FilterState& s);

class Filter {
 public:
  virtual ~Filter() = default;
  /// The filter type (as makeFilter takes it); the same object for the filter's lifetime.
  virtual const std::string& name() const = 0;
  /// Current state (first three entries x, y, theta), covariance and status.
  FilterState state() const {
    FilterState s;
    stateInto(s);
    return s;
  }
  /// The same values as state(), into out, reusing its storage (the engine's per-message path).
  virtual void stateInto(FilterState& out) const = 0;
  /// Starts from another filter's state: the first three states and their covariance are
  /// copied; states this filter has but the source lacks take their initial values; states
  /// the source has but this filter lacks are dropped (hot swap).
  virtual void initialize(const FilterState& from) = 0;
  /// Time update with one odometry increment.
  virtual void predict(const OdometryInput& odo) = 0;
  /// Whether the filter uses this kind of measurement. The engine hands a filter only the
  /// measurements it uses and publishes decisions for those only. Default: the ruler (the
  /// magnetic-ruler family, including dead reckoning, which reports "dead_reckoning").
  virtual bool uses(Measurement m) const { return m == Measurement::Ruler; }
  /// Measurement update with one ruler detection; returns the gate decision (dead reckoning
  /// returns a decision with accepted = false, reason "dead_reckoning"). Default, for filters
  /// that do not use the ruler (the engine does not call it then): not accepted, reason
  /// "ignored".
  virtual GateDecision update(const RulerDetection& det);
  /// One IMU sample. Returns the decision on the measurement it carries (the magnetometer
  /// heading) when the filter used one; nullopt when nothing was gated (default: ignored).
  virtual std::optional<GateDecision> update(const ImuInput&) { return std::nullopt; }
  /// One GPS fix; returns the gate decision when the filter uses GPS (default: ignored).
  virtual std::optional<GateDecision> update(const GpsInput&) { return std::nullopt; }
  /// One range-bearing landmark observation (default: ignored).
  virtual std::optional<GateDecision> update(const LandmarkObservation&) { return std::nullopt; }
  /// One range-only beacon measurement (default: ignored).
  virtual std::optional<GateDecision> update(const BeaconRange&) { return std::nullopt; }
  /// IMU samples not used because their forward acceleration reached gnss.accel_saturation
  /// (the GNSS filters; 0 for the others). The engine reports each saturated stretch.
  virtual int64_t saturatedImuSamples() const { return 0; }
  /// The re-localization the last measurement caused, once (cleared by the call); default none.
  virtual std::optional<Relocalization> takeRelocalization() { return std::nullopt; }
  /// Status only: what state().status returns, without copying the state (per-message path).
  virtual FilterStatus status() const { return state().status; }
  /// Batched time update (fusion.output_every > 1): adds one odometry increment to a pending
  /// SE(2) increment instead of updating the state. False when this filter cannot batch (the
  /// caller then calls predict()). state() does not include a pending increment until
  /// applyAccumulated() applies it with one time update.
  virtual bool accumulate(const OdometryInput&) { return false; }
  virtual void applyAccumulated() {}
  /// Re-initializes from an absolute pose fix (three-landmark fix): default sets x, y, theta
  /// and their covariance like SetPose (cross-covariances to other states zeroed). Returns
  /// false when the fix was not applied.
  virtual bool applyFix(const PoseFix& fix);
  /// An odometry gap (the engine calls it before the first increment after the gap, which then
  /// covers its own period only). Default: the constant-velocity bridge (bridgeIncrement) through
  /// predict(), then bridgeNoise added to the pose covariance by addPoseNoise(), and the status
  /// DeadReckoning until a measurement is accepted again. Returns what was done, for the event.
  virtual std::string bridgeOdometryGap(const OdometryGap& gap);

 protected:
  /// Adds Q to the covariance of (x, y, theta) and marks the state DeadReckoning until the next
  /// accepted measurement (Lockout stays Lockout). Default: through state() and initialize().
  virtual void addPoseNoise(const Mat3& Q);
};

/// Builds a filter of cfg.type over the marker map (shared, not copied: filters of one map share
/// its index). Throws std::invalid_argument for an unknown type or an invalid configuration
/// (message names the parameter).
std::unique_ptr<Filter> makeFilterOver(const FilterConfig& cfg, const SharedMapIndex& map);
/// The same over map, indexed for this filter alone.
std::unique_ptr<Filter> makeFilter(const FilterConfig& cfg, const MarkerMap& map);

/// Why a state cannot start a filter ("" when it can): fewer than 3 entries or a P of another
/// size, a value that is not finite, a position beyond kMaxAbsPosition or a variance beyond
/// kMaxVariance, a P that is not symmetric or not positive semi-definite, or a pose variance (x,
/// y, theta) that is not > 0. Hand-overs, checkpoints, fixes and set_pose are checked with it: a
/// zero or negative covariance froze the filter (every measurement refused), and a finite but
/// absurd one (x = 1e308, a variance of 1e400 from a standard deviation of 1e200) made its next
/// states infinite.
std::string unusableState(const FilterState& s);
/// [m] |x| and |y| of a usable state: 10,000 km, more than any local frame spans.
inline constexpr double kMaxAbsPosition = 1e7;
/// Largest usable variance (any state): kMaxAbsPosition squared.
inline constexpr double kMaxVariance = kMaxAbsPosition * kMaxAbsPosition;

/// A self-calibration state of a filter's state (FilterConfig::Calibration): its name without
/// the "cal_" its state name starts with (odo_scale, yaw_rate_scale, yaw_rate_bias, beacon_bias,
/// beacon_bias_<id>), its estimate and 1 sigma.
struct CalibrationValue {
  std::string name;
  double value = 0.0, sigma = 0.0;
};
/// The self-calibration states of s, in state order (none when it has none).
std::vector<CalibrationValue> calibrationValues(const FilterState& s);
/// "calibration: odo_scale -0.012 +- 0.004, ..." ("" when s has no calibration state).
std::string calibrationSummary(const FilterState& s);

/// Names accepted by makeFilter.
std::vector<std::string> filterTypes();
/// The GNSS filters ("tvekf", "ukf_gps"): the ones that read fusion.filter.gnss.
bool isGnssFilter(const std::string& type);
/// filterTypes() as "a, b, c" (help texts, error messages).
std::string filterTypeList();

}  // namespace lcmloc::core
