#pragma once
// What the GNSS filters ("tvekf": tvekf_filter.cpp, "ukf_gps": gps_ukf_filter.cpp) share: the
// state (x, y, theta, speed, distance), the odometry time step with the IMU's forward
// acceleration, the magnetometer and GPS measurements behind their gates, the lock-out
// detectors, the GPS-course heading aid (gnss_filters.cpp) and the re-localization from refused
// fixes (gnss_relocalization.cpp). Not installed; src/ only.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "filter_internal.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::core::gnss_filter {

enum : int { kX = 0, kY = 1, kTheta = 2, kSpeed = 3, kDistance = 4, kN = 5 };

/// The self-calibration states (FilterConfig::Calibration) a configuration switches on, appended
/// after the five states in this order: odometer scale k (the encoder's distance and speed, in
/// the encoder's units, times 1 + k are the true ones), steering bias s (the true steering is
/// the measured one minus s) and magnetometer heading bias m (a first-order Markov process: the
/// magnetometer heading is theta + m) and the forward accelerometer's bias b_a (it reads the
/// acceleration plus b_a; a random walk). -1: switched off.
struct GnssCalibration {
  int odo_scale = -1, steering_bias = -1, mag_bias = -1, accel_bias = -1;
  std::vector<std::string> names;  ///< x, y, theta, speed, distance, then "cal_..." of each on
  Eigen::VectorXd x0, p0;          ///< prior means and variances of every state (the first five: 0)
  FilterConfig::Calibration cfg;
  int size() const { return static_cast<int>(names.size()); }
  static GnssCalibration of(const FilterConfig& c);
  /// 1 + k of state s (1 without the state).
  template <class V>
  double scale(const V& s) const { return odo_scale >= 0 ? 1.0 + s[odo_scale] : 1.0; }
  template <class V>
  double steeringBias(const V& s) const { return steering_bias >= 0 ? s[steering_bias] : 0.0; }
  template <class V>
  double magBias(const V& s) const { return mag_bias >= 0 ? s[mag_bias] : 0.0; }
  template <class V>
  double accelBias(const V& s) const { return accel_bias >= 0 ? s[accel_bias] : 0.0; }
  /// Markov factor of m over T seconds.
  double magDecay(double T) const { return std::exp(-T / cfg.mag_bias_tau); }
  /// Process-noise variances of the calibration states over a step of T seconds and ds metres
  /// (encoder), into the diagonal entries of q at their indices.
  template <class D>
  void addProcessNoise(double T, double ds, D& q) const {
    if (odo_scale >= 0) q(odo_scale, odo_scale) += cfg.odo_scale_rw * cfg.odo_scale_rw * std::abs(ds);
    if (steering_bias >= 0) q(steering_bias, steering_bias) += cfg.steering_bias_rw * cfg.steering_bias_rw * T;
    if (accel_bias >= 0) q(accel_bias, accel_bias) += cfg.accel_bias_rw * cfg.accel_bias_rw * T;
    if (mag_bias >= 0) {
      const double phi = magDecay(T);
      q(mag_bias, mag_bias) += cfg.mag_bias_std * cfg.mag_bias_std * (1.0 - phi * phi);
    }
  }
};

/// Consecutive gate rejections of one measurement kind. Every n-th rejection in a row is a
/// lock-out (status LOCKOUT). For the magnetometer the caller then inflates the heading
/// covariance, so the gate opens within a bounded number of rejections; for GPS it does not
/// (the filter re-localizes from agreeing fixes instead: RejectedFixes). An acceptance ends it.
class Lockout {
 public:
  explicit Lockout(int n) : n_(n) {}
  /// Records a rejection; true when the covariance is to be inflated now.
  bool reject() {
    ++count_;
    if (n_ <= 0 || count_ % n_ != 0) return false;
    active_ = true;
    return true;
  }
  void accept() { count_ = 0; active_ = false; }
  bool active() const { return active_; }
 private:
  int n_;
  int count_ = 0;
  bool active_ = false;
};

/// GPS fixes the gate refused since the last accepted one (at most kCapacity, none more than
/// kMaxAgeS older than the newest), each with the dead-reckoned motion up to it: the evidence a
/// lost filter re-localizes from. Fixes agree when, each carried forward to the newest by the
/// dead-reckoned displacement between them (odometry distance along the filter's heading,
/// rotated by the heading error a long enough chord reveals), each lies within the chi-square
/// gate of the newest, with the variance of both fixes plus the heading uncertainty times the
/// displacement squared.
class RejectedFixes {
 public:
  static constexpr std::size_t kCapacity = 8;
  static constexpr double kMaxAgeS = 30.0;
  /// A chord (of the fixes and of the dead reckoning) this many times the two fixes' combined
  /// sigma long gives the heading (its 1 sigma then at most 1/kChordSigmas rad).
  static constexpr double kChordSigmas = 3.0;
  struct Agreement {
    int fixes = 1;             ///< fixes that agree with the newest, the newest included
    int64_t first_utime = 0;   ///< the oldest of them
    double spread = 0;         ///< largest distance of one carried forward from the newest [m]
    bool heading = false;      ///< heading error from the chord of the fixes (dtheta)
    double dtheta = 0;         ///< heading error: chord of the fixes minus dead-reckoned chord [rad]
    double heading_var = 0;    ///< variance of the heading after it: of dtheta, or what the agreement bounds [rad^2]
  };
  void clear() {
    w_.clear();
    dr_.setZero();
    hvar_ = 0;
  }
  bool empty() const { return w_.empty(); }
  /// One odometry step while the window holds fixes: distance ds along heading theta, and the
  /// heading variance the step added.
  void move(double ds, double theta, double step_heading_var);
  /// Adds a refused fix (1 sigma sd per axis) and returns the largest agreement of the window
  /// with it; heading_var is the filter's heading variance, gate the 2-dof chi-square gate.
  Agreement add(int64_t utime, const Vec2& z, double sd, double heading_var, double gate);

 private:
  struct Fix {
    int64_t utime;
    Vec2 z;
    double var;
    Vec2 dr;
    double hvar;
  };
  /// The fixes that agree with the newest, carried forward with the filter's heading (anchor
  /// npos) or rotated by the heading error of the chord from w_[anchor] to the newest.
  Agreement agreeing(std::size_t anchor, double heading_var, double gate) const;
  std::deque<Fix> w_;
  Vec2 dr_ = Vec2::Zero();  ///< dead-reckoned position since the window began [m]
  double hvar_ = 0;         ///< heading variance added since the window began [rad^2]
};

/// One odometry interval as the time update sees it.
struct Step {
  double T = 0;          ///< [s]
  double a = 0;          ///< forward acceleration over the interval [m/s^2]
  double a_std = 0;      ///< its 1 sigma [m/s^2]
  bool has_accel = true;  ///< a is the accelerometer's (false: no sample in the interval, a = 0)
  bool has_steering = true;
  double psi = 0;        ///< steering [rad]
  double delta_theta = 0;  ///< heading increment when !has_steering [rad]
};

/// What both GNSS filters share: state names, timing, the IMU acceleration of each interval,
/// the encoder's accumulated distance, gates, lock-outs and the status. A filter supplies its
/// state's storage, its time update and its heading and position corrections.
class GnssFilterBase : public Filter {
 public:
  explicit GnssFilterBase(const FilterConfig& c)
      : cfg_(c), g_(c.gnss), cal_(GnssCalibration::of(c)),
        gate1_(c.gate.enabled ? c.gate.threshold(1) : std::numeric_limits<double>::infinity()),
        gate2_(c.gate.enabled ? c.gate.threshold(2) : std::numeric_limits<double>::infinity()),
        gps_lock_(c.gnss.gps_lockout_rejections), mag_lock_(c.gnss.mag_lockout_rejections) {}

  bool uses(Measurement m) const override { return m != Measurement::Ruler; }

  void stateInto(FilterState& s) const override {
    s.utime = utime_;
    fillState(s.x, s.P);
    detail::setNames(s, names());
    s.status = status();
  }

  void initialize(const FilterState& from) override;
  void predict(const OdometryInput& odo) override;
  std::optional<GateDecision> update(const ImuInput& m) override;
  std::optional<GateDecision> update(const GpsInput& gps) override;

  /// An odometry gap: the time update of the next increment spans it already (position from
  /// speed and heading, speed from the IMU's acceleration); the encoder distance, which lacks the
  /// gap's travel, is re-based there instead of pulling the distance and speed back.
  std::string bridgeOdometryGap(const OdometryGap& gap) override {
    encoder_gap_s_ = gap.seconds;
    return name() + ": speed and heading carry the position over the gap; encoder distance re-based";
  }

  /// IMU samples whose forward acceleration was saturated or not finite (not used).
  int64_t saturatedImuSamples() const override { return saturated_; }
  /// The re-localization the last GPS fix caused, once.
  std::optional<Relocalization> takeRelocalization() override { return std::exchange(relocalized_, std::nullopt); }
  /// GPS-course heading aid (gnss.course_distance, tvekf): heading updates accepted / gated.
  int64_t courseAccepted() const { return course_accepted_; }
  int64_t courseRejected() const { return course_rejected_; }

 protected:
  const std::vector<std::string>& names() const { return cal_.names; }
  void initialState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const;
  FilterStatus status() const override;
  /// Heading variance added over a step by the steering noise, the speed uncertainty (through
  /// eq. 10) and the heading random walk.
  double headingNoise(const Step& st, double v, double Pv) const;
  double headingIncrement(const Step& st, double v) const;

  virtual void fillState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const = 0;
  virtual void setState(const Eigen::VectorXd& x, const Eigen::MatrixXd& P) = 0;
  virtual void timeUpdate(const Step& st) = 0;
  /// Fill d (innovation, mahalanobis, reason, accepted) and correct if it passes the gate. A
  /// magnetometer heading (magnetic) measures theta + m with the magnetometer bias state, a
  /// GPS-course heading theta.
  virtual void headingUpdate(double z, double r, GateDecision& d, bool magnetic) = 0;
  virtual double heading() const = 0;
  virtual void positionUpdate(const Vec2& z, double r, GateDecision& d) = 0;
  virtual void inflateHeading() = 0;
  /// Adds the position random walk of dt seconds to the position covariance.
  virtual void growPosition(double dt) = 0;

  /// GPS-course heading aid (for a vehicle without magnetometer): between two accepted fixes
  /// at least gnss.course_distance of travel apart, the direction of the GPS chord minus the
  /// direction of the dead-reckoned chord (odometry integrated along the filter's heading over
  /// the same stretch) is the heading error, whatever the path's curvature, as long as that error
  /// was constant over the stretch. Fused as a heading measurement theta + error with variance
  /// 2 sd^2 / |chord|^2 (+ gnss.course_std^2) behind the 1-dof gate; then re-anchored.
  void courseAid(const Vec2& z, double sd);
  /// A refused fix: into the window; re-localizes when enough fixes agree (two while no fix
  /// confirmed the state the filter started from, its configured pose or another's state;
  /// three after), else counts towards the lock-out.
  void refusedFix(const GpsInput& gps, const Vec2& z, double sd, GateDecision& d);
  /// Position from the newest fix (sigma sd), heading from the chord or kept with its sigma
  /// opened to what the agreement bounds, speed and distance kept; their cross-covariances with
  /// the pose dropped.
  void relocalize(const Vec2& z, double sd, const RejectedFixes::Agreement& a, int64_t utime);

  FilterConfig cfg_;
  GnssConfig g_;
  GnssCalibration cal_;
  bool use_course_ = false;  ///< the GPS-course heading aid applies (tvekf)
  double gate1_, gate2_;  ///< chi-square gates of 1-D (heading) and 2-D (position) innovations
  double enc_sum_ = 0;    ///< encoder distance accumulated since the start [m] (eq. 5's s(k))
  double encoder_gap_s_ = 0;  ///< an odometry gap the next increment follows [s] (bridgeOdometryGap)

 private:
  int64_t utime_ = 0;
  bool have_odo_time_ = false;
  bool clock_from_state_ = false;  ///< the clock runs from the state initialize() took
  static constexpr int64_t kMaxHandOverGapUs = 500000;
  int64_t last_odo_utime_ = 0;
  double acc_sum_ = 0;
  int acc_n_ = 0;
  int64_t saturated_ = 0;
  bool have_fix_ = false;
  int64_t last_fix_utime_ = 0;
  int64_t last_position_utime_ = 0;  ///< time the position prediction has reached
  Lockout gps_lock_, mag_lock_;
  RejectedFixes rejected_;
  bool confirmed_ = false;  ///< a fix was accepted (or re-localized) since the state was set
  std::optional<Relocalization> relocalized_;
  bool course_open_ = false;
  Vec2 course_anchor_ = Vec2::Zero(), course_dr_ = Vec2::Zero();
  double course_dist_ = 0;
  int64_t course_accepted_ = 0, course_rejected_ = 0;
};

/// The time-varying EKF of Choi and Kong ("tvekf"; tvekf_filter.cpp).
std::unique_ptr<Filter> makeTvEkf(const FilterConfig& cfg);
/// The UKF over the same sensors ("ukf_gps"; gps_ukf_filter.cpp).
std::unique_ptr<Filter> makeGpsUkf(const FilterConfig& cfg);

}  // namespace lcmloc::core::gnss_filter
