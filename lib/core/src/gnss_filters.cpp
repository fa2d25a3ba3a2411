// The GNSS filters: the time-varying EKF of Choi and Kong (seeds/002, "tvekf") and a UKF over
// the same sensors ("ukf_gps"). Both: state (x, y, theta, speed, distance); odometry (encoder
// distance + steering) drives the time update together with the forward acceleration of the
// IMU; the magnetometer heading and GPS fixes are measurements, each behind a chi-square gate,
// each with its own lock-out detector. Derivations and measured results: docs/tvekf.md.
#include <algorithm>
#include <cmath>
#include <utility>
#include <limits>
#include <stdexcept>

#include "filter_internal.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/gnss_model.hpp"
#include "lcmloc/core/ukf.hpp"

namespace lcmloc::core {
namespace {

using detail::decision;

constexpr double kInf = std::numeric_limits<double>::infinity();
enum : int { kX = 0, kY = 1, kTheta = 2, kSpeed = 3, kDistance = 4, kN = 5 };

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("filter config: " + what);
}

void validateGnss(const FilterConfig& c) {
  const GnssConfig& g = c.gnss;
  auto pos = [](double v) { return std::isfinite(v) && v > 0; };
  auto nonneg = [](double v) { return std::isfinite(v) && v >= 0; };
  require(pos(c.wheelbase), "wheelbase must be > 0");
  require(c.initial_pose.allFinite(), "initial_pose must be finite");
  require(c.p0_diag.allFinite() && (c.p0_diag.array() > 0).all(), "p0_diag must be > 0");
  require(std::isfinite(c.lockout_inflation) && c.lockout_inflation >= 1,
          "lockout_inflation must be >= 1");
  require(std::isfinite(c.lockout_max_std) && c.lockout_max_std > 0, "lockout_max_std must be > 0");
  if (c.gate.value) require(pos(*c.gate.value), "gate.value must be > 0");
  require(c.gate.probability > 0 && c.gate.probability < 1, "gate.probability must be in (0, 1)");
  require(c.gate.dof >= 0 && c.gate.dof <= 10, "gate.dof must be in 0..10");
  require(std::isfinite(c.sigma.alpha) && c.sigma.alpha > 0, "sigma.alpha must be > 0");
  require(std::isfinite(c.sigma.beta) && std::isfinite(c.sigma.kappa), "sigma must be finite");
  require(c.sigma.alpha * c.sigma.alpha * (kN + c.sigma.kappa) > 0,
          "sigma: alpha^2 (n + kappa) must be > 0");
  require(pos(g.accel_std), "gnss.accel_std must be > 0");
  require(nonneg(g.accel_saturation), "gnss.accel_saturation must be >= 0");
  require(pos(g.accel_unknown_std), "gnss.accel_unknown_std must be > 0");
  require(pos(g.encoder_std), "gnss.encoder_std must be > 0");
  require(nonneg(g.steering_std), "gnss.steering_std must be >= 0");
  require(nonneg(g.heading_rw), "gnss.heading_rw must be >= 0");
  require(nonneg(g.position_rw), "gnss.position_rw must be >= 0");
  require(pos(g.mag_std), "gnss.mag_std must be > 0");
  require(std::isfinite(g.declination) && std::abs(g.declination) <= M_PI,
          "gnss.declination must be within [-pi, pi]");
  require(pos(g.gps_std), "gnss.gps_std must be > 0");
  require(pos(g.speed_std0), "gnss.speed_std0 must be > 0");
  require(g.gps_lockout_rejections >= 0, "gnss.gps_lockout_rejections must be >= 0");
  require(g.mag_lockout_rejections >= 0, "gnss.mag_lockout_rejections must be >= 0");
  require(nonneg(g.coast_timeout), "gnss.coast_timeout must be >= 0");
  require(nonneg(g.course_distance), "gnss.course_distance must be >= 0");
  require(nonneg(g.course_std), "gnss.course_std must be >= 0");
}

/// Consecutive gate rejections of one measurement kind. Every n-th rejection in a row is a
/// lock-out: the caller inflates the covariance of the states that measurement observes, so
/// the gate, which compares the innovation with that covariance, opens within a bounded
/// number of rejections (the inflation grows geometrically). An acceptance ends it.
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


/// One odometry interval as the time update sees it.
struct Step {
  double T = 0;          ///< [s]
  double a = 0;          ///< forward acceleration over the interval [m/s^2]
  double a_std = 0;      ///< its 1 sigma [m/s^2]
  bool has_steering = true;
  double psi = 0;        ///< steering [rad]
  double delta_theta = 0;  ///< heading increment when !has_steering [rad]
};

/// What both GNSS filters share: state names, timing, the IMU acceleration of each interval,
/// the encoder's accumulated distance, gates, lock-outs and the status.
class GnssFilterBase : public Filter {
 public:
  explicit GnssFilterBase(const FilterConfig& c)
      : cfg_(c), g_(c.gnss),
        gate1_(c.gate.enabled ? c.gate.threshold(1) : kInf),
        gate2_(c.gate.enabled ? c.gate.threshold(2) : kInf),
        gps_lock_(c.gnss.gps_lockout_rejections), mag_lock_(c.gnss.mag_lockout_rejections) {}

  bool uses(Measurement m) const override { return m != Measurement::Ruler; }

  void stateInto(FilterState& s) const override {
    s.utime = utime_;
    fillState(s.x, s.P);
    detail::setNames(s, names());
    s.status = status();
  }

  void initialize(const FilterState& from) override {
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(x, P);
    detail::copyMatching(from, names(), x, P);
    setState(x, P);
    utime_ = from.utime;
    enc_sum_ = x[kDistance];
    encoder_gap_s_ = 0;
    // A state of a time (hand-over, fix, set_pose, checkpoint): the next increment is the motion
    // since then, if it comes within kMaxHandOverGapUs (a daemon started from a checkpoint after
    // a crash does not know how the vehicle moved meanwhile: resume_gap). A state of no time (a
    // filter just made): the first increment starts the clock.
    have_odo_time_ = from.utime > 0;
    clock_from_state_ = have_odo_time_;
    last_odo_utime_ = from.utime;
    acc_sum_ = 0;
    acc_n_ = 0;
    have_fix_ = false;
    last_position_utime_ = from.utime;
    course_open_ = false;
    gps_lock_ = Lockout(g_.gps_lockout_rejections);
    mag_lock_ = Lockout(g_.mag_lockout_rejections);
  }

  void predict(const OdometryInput& odo) override {
    if (!std::isfinite(odo.delta_s) ||
        !(odo.has_steering ? std::isfinite(odo.steering) : std::isfinite(odo.delta_theta)))
      return;
    utime_ = std::max(utime_, odo.utime);
    const bool from_state = std::exchange(clock_from_state_, false);
    if (!have_odo_time_ || (from_state && odo.utime - last_odo_utime_ > kMaxHandOverGapUs)) {
      have_odo_time_ = true;  // the first increment only starts the clock and the encoder sum
      last_odo_utime_ = odo.utime;
      encoder_gap_s_ = 0;
      return;
    }
    if (encoder_gap_s_ > 0) {
      // After an odometry gap the encoder did not see the distance of the gap: its sum goes on
      // from the distance the filter predicts over the gap (speed from the IMU's acceleration).
      Eigen::VectorXd x;
      Eigen::MatrixXd P;
      fillState(x, P);
      enc_sum_ = x[kDistance] + x[kSpeed] * encoder_gap_s_;
      encoder_gap_s_ = 0;
    }
    enc_sum_ += odo.delta_s;
    Step st;
    st.T = static_cast<double>(odo.utime - last_odo_utime_) * 1e-6;
    if (!(st.T > 0)) return;
    last_odo_utime_ = odo.utime;
    if (acc_n_ > 0) {
      st.a = acc_sum_ / acc_n_;
      st.a_std = g_.accel_std;
    } else {
      st.a = 0.0;
      st.a_std = g_.accel_unknown_std;
    }
    acc_sum_ = 0;
    acc_n_ = 0;
    st.has_steering = odo.has_steering;
    st.psi = odo.steering;
    st.delta_theta = odo.delta_theta;
    timeUpdate(st);
    last_position_utime_ = std::max(last_position_utime_, odo.utime);
    if (course_open_) {  // dead-reckoned displacement along the filter's heading since the anchor fix
      const double th = heading();
      course_dr_ += odo.delta_s * Vec2(std::cos(th), std::sin(th));
      course_dist_ += std::abs(odo.delta_s);
    }
  }

  std::optional<GateDecision> update(const ImuInput& m) override {
    utime_ = std::max(utime_, m.utime);
    const double ax = m.accel[0];
    if (std::isfinite(ax) && !(g_.accel_saturation > 0 && std::abs(ax) >= g_.accel_saturation)) {
      acc_sum_ += ax;
      ++acc_n_;
    } else {
      ++saturated_;
    }
    if (!g_.use_magnetometer) return std::nullopt;
    GateDecision d = decision(m.utime, m.sensor, m.seq, gate1_);
    const double z = gnss::magnetometerHeading(m.mag, g_.declination);
    if (!std::isfinite(z)) {
      d.reason = "bad_input";
      return d;
    }
    headingUpdate(z, g_.mag_std * g_.mag_std, d);
    if (d.reason == "gate" && mag_lock_.reject()) inflateHeading();
    if (d.accepted) mag_lock_.accept();
    return d;
  }

  std::optional<GateDecision> update(const GpsInput& gps) override {
    utime_ = std::max(utime_, gps.utime);
    GateDecision d = decision(gps.utime, gps.sensor, gps.seq, gate2_);
    if (!gps.has_fix) {
      d.reason = "no_fix";
      return d;
    }
    if (!std::isfinite(gps.x) || !std::isfinite(gps.y)) {
      d.reason = "bad_input";
      return d;
    }
    const double sd = std::isfinite(gps.position_std) && gps.position_std > 0 ? gps.position_std
                                                                                : g_.gps_std;
    // Position random walk over the time no odometry step covered (none at all for a GPS-only
    // run; at most one odometry period otherwise).
    if (gps.utime > last_position_utime_) {
      if (last_position_utime_ > 0) growPosition(static_cast<double>(gps.utime - last_position_utime_) * 1e-6);
      last_position_utime_ = gps.utime;
    }
    positionUpdate(Vec2(gps.x, gps.y), sd * sd, d);
    if (d.reason == "gate" && gps_lock_.reject()) inflatePosition();
    if (d.accepted) {
      gps_lock_.accept();
      have_fix_ = true;
      last_fix_utime_ = gps.utime;
      if (use_course_ && g_.course_distance > 0) courseAid(Vec2(gps.x, gps.y), sd);
    }
    return d;
  }

  /// An odometry gap: the time update of the next increment spans it already (position from
  /// speed and heading, speed from the IMU's acceleration); the encoder distance, which lacks the
  /// gap's travel, is re-based there instead of pulling the distance and speed back.
  std::string bridgeOdometryGap(const OdometryGap& gap) override {
    encoder_gap_s_ = gap.seconds;
    return name() + ": speed and heading carry the position over the gap; encoder distance re-based";
  }

  /// IMU samples whose forward acceleration was saturated or not finite (not used).
  int64_t saturatedImuSamples() const override { return saturated_; }
  /// GPS-course heading aid (gnss.course_distance, tvekf): heading updates accepted / gated.
  int64_t courseAccepted() const { return course_accepted_; }
  int64_t courseRejected() const { return course_rejected_; }

 protected:
  static const std::vector<std::string>& names() {
    static const std::vector<std::string> n{"x", "y", "theta", "speed", "distance"};
    return n;
  }
  void initialState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const {
    x = Eigen::VectorXd::Zero(kN);
    P = Eigen::MatrixXd::Zero(kN, kN);
    x.head<3>() = cfg_.initial_pose;
    x[kTheta] = wrapAngle(x[kTheta]);
    P.topLeftCorner<3, 3>() = cfg_.p0_diag.asDiagonal();
    P(kSpeed, kSpeed) = g_.speed_std0 * g_.speed_std0;
    P(kDistance, kDistance) = g_.encoder_std * g_.encoder_std;
  }
  FilterStatus status() const override {
    if (gps_lock_.active() || mag_lock_.active()) return FilterStatus::Lockout;
    const auto timeout = static_cast<int64_t>(g_.coast_timeout * 1e6);
    if (!have_fix_ || utime_ - last_fix_utime_ > timeout) return FilterStatus::DeadReckoning;
    return FilterStatus::Ok;
  }
  /// Heading variance added over a step by the steering noise, the speed uncertainty (through
  /// eq. 10) and the heading random walk.
  double headingNoise(const Step& st, double v, double Pv) const {
    double q = g_.heading_rw * g_.heading_rw * st.T;
    if (st.has_steering) {
      const double c = std::cos(st.psi), t = std::tan(st.psi), L = cfg_.wheelbase;
      const double dv = st.T * t / L, dpsi = st.T * v / (L * c * c);
      q += dv * dv * Pv + dpsi * dpsi * g_.steering_std * g_.steering_std;
    }
    return q;
  }
  double headingIncrement(const Step& st, double v) const {
    return st.has_steering ? st.T * gnss::headingRate(v, st.psi, cfg_.wheelbase) : st.delta_theta;
  }

  virtual void fillState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const = 0;
  virtual void setState(const Eigen::VectorXd& x, const Eigen::MatrixXd& P) = 0;
  virtual void timeUpdate(const Step& st) = 0;
  /// Fill d (innovation, mahalanobis, reason, accepted) and correct if it passes the gate.
  virtual void headingUpdate(double z, double r, GateDecision& d) = 0;
  virtual double heading() const = 0;
  virtual void positionUpdate(const Vec2& z, double r, GateDecision& d) = 0;
  virtual void inflateHeading() = 0;
  virtual void inflatePosition() = 0;
  /// Adds the position random walk of dt seconds to the position covariance.
  virtual void growPosition(double dt) = 0;

  /// GPS-course heading aid (for a vehicle without magnetometer): between two accepted fixes
  /// at least gnss.course_distance of travel apart, the direction of the GPS chord minus the
  /// direction of the dead-reckoned chord (odometry integrated along the filter's heading over
  /// the same stretch) is the heading error, whatever the path's curvature, as long as that error
  /// was constant over the stretch. Fused as a heading measurement theta + error with variance
  /// 2 sd^2 / |chord|^2 (+ gnss.course_std^2) behind the 1-dof gate; then re-anchored.
  void courseAid(const Vec2& z, double sd) {
    if (!course_open_ || course_dist_ >= g_.course_distance) {
      if (course_open_) {
        const Vec2 c = z - course_anchor_;
        // a chord much shorter than the travel (a U-turn, reversing back and forth) says little
        if (c.norm() >= 0.5 * course_dist_ && course_dr_.norm() >= 0.5 * course_dist_) {
          const double err = wrapAngle(std::atan2(c.y(), c.x()) - std::atan2(course_dr_.y(), course_dr_.x()));
          const double r = 2.0 * sd * sd / c.squaredNorm() + g_.course_std * g_.course_std;
          GateDecision d = decision(last_fix_utime_, "GPS_COURSE", 0, gate1_);
          headingUpdate(wrapAngle(heading() + err), r, d);
          if (d.accepted) {
            ++course_accepted_;
            mag_lock_.accept();
          } else {
            ++course_rejected_;
            if (d.reason == "gate" && mag_lock_.reject()) inflateHeading();
          }
        }
      }
      course_open_ = true;
      course_anchor_ = z;
      course_dr_.setZero();
      course_dist_ = 0;
    }
  }

  FilterConfig cfg_;
  GnssConfig g_;
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
  bool course_open_ = false;
  Vec2 course_anchor_ = Vec2::Zero(), course_dr_ = Vec2::Zero();
  double course_dist_ = 0;
  int64_t course_accepted_ = 0, course_rejected_ = 0;
};

// ---------------------------------------------------------------------------------------------
/// The time-varying EKF of §2 as a cascade of three small filters with their own covariances
/// (the paper's decoupling; cross-covariances between the blocks are neglected):
///  §2.1 kinematic KF of [s, v] from the forward acceleration, corrected by the encoder distance;
///  §2.2 heading predicted by eq. 10 from v and the steering, corrected by the magnetometer
///       heading with the scalar gain L = P_theta^- / (P_theta^- + R_mag) of every step;
///  §2.3 position predicted by eq. 17 from v and theta, corrected by GPS with the gain
///       J = P_p^- (P_p^- + R_gps)^-1 of every step (eq. 21 when the axes are uncorrelated).
class TvEkf final : public GnssFilterBase {
 public:
  explicit TvEkf(const FilterConfig& c) : GnssFilterBase(c) {
    use_course_ = true;
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(x, P);
    setState(x, P);
  }
  const std::string& name() const override {
    static const std::string n = "tvekf";
    return n;
  }
  double heading() const override { return th_; }

 protected:
  void fillState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const override {
    x.resize(kN);
    x << p_, th_, sv_[1], sv_[0];
    P = Eigen::MatrixXd::Zero(kN, kN);
    P.topLeftCorner<2, 2>() = Pp_;
    P(kTheta, kTheta) = Pth_;
    P(kSpeed, kSpeed) = Psv_(1, 1);
    P(kDistance, kDistance) = Psv_(0, 0);
    P(kSpeed, kDistance) = P(kDistance, kSpeed) = Psv_(0, 1);
  }
  void setState(const Eigen::VectorXd& x, const Eigen::MatrixXd& P) override {
    p_ = x.head<2>();
    Pp_ = P.topLeftCorner<2, 2>();
    th_ = wrapAngle(x[kTheta]);
    Pth_ = P(kTheta, kTheta);
    sv_ << x[kDistance], x[kSpeed];
    Psv_ << P(kDistance, kDistance), P(kDistance, kSpeed), P(kSpeed, kDistance), P(kSpeed, kSpeed);
  }

  void timeUpdate(const Step& st) override {
    const double T = st.T, v = sv_[1], Pv = Psv_(1, 1);
    // §2.3, eq. 17 with v(k), theta(k); covariance through its Jacobian in (v, theta) (eq. 22-24).
    const double c = std::cos(th_), s = std::sin(th_);
    Mat2 G;
    G << T * c, -v * T * s, T * s, v * T * c;
    p_ = gnss::positionStep(p_, v, th_, T);
    Pp_ = Pp_ + G * Vec2(Pv, Pth_).asDiagonal() * G.transpose();
    Pp_.diagonal().array() += g_.position_rw * g_.position_rw * T;
    // §2.2, eq. 10 (a priori heading) and eq. 13 (its variance).
    Pth_ += headingNoise(st, v, Pv);
    th_ = wrapAngle(th_ + headingIncrement(st, v));
    // §2.1, eq. 6: a priori [s, v]; process noise of the acceleration through B.
    const Mat2 A = gnss::kinematicA(T);
    const Vec2 B = gnss::kinematicB(T);
    sv_ = gnss::kinematicStep(sv_, st.a, T);
    Psv_ = A * Psv_ * A.transpose() + B * B.transpose() * (st.a_std * st.a_std);
    // eq. 7: correction by the encoder distance s(k+1) = C x + noise; F = P C' (C P C' + R)^-1.
    const double S = Psv_(0, 0) + g_.encoder_std * g_.encoder_std;
    const Vec2 F = Psv_.col(0) / S;
    sv_ += F * (enc_sum_ - sv_[0]);
    Psv_ -= F * Psv_.row(0);
    Psv_ = 0.5 * (Psv_ + Psv_.transpose()).eval();
  }

  void headingUpdate(double z, double r, GateDecision& d) override {
    const double v = wrapAngle(z - th_);
    const double S = Pth_ + r;
    d.innovation = Eigen::VectorXd::Constant(1, v);
    d.mahalanobis = v * v / S;
    if (!(d.mahalanobis <= gate1_)) {
      d.reason = "gate";
      return;
    }
    const double L = Pth_ / S;  // eq. 11-12: the time-varying gain, recomputed every sample
    th_ = wrapAngle(th_ + L * v);
    Pth_ *= 1.0 - L;
    d.accepted = true;
    d.reason = std::isfinite(gate1_) ? "accepted" : "ungated";
  }

  void positionUpdate(const Vec2& z, double r, GateDecision& d) override {
    const Vec2 v = z - p_;
    const Mat2 S = Pp_ + r * Mat2::Identity();
    Mat2 S_inv;
    if (!inverseSpd<2>(S, S_inv)) {
      d.reason = "bad_input";
      return;
    }
    d.innovation = v;
    d.mahalanobis = v.dot(S_inv * v);
    if (!(d.mahalanobis <= gate2_)) {
      d.reason = "gate";
      return;
    }
    const Mat2 J = Pp_ * S_inv;  // eq. 20-21, recomputed every fix
    p_ += J * v;
    Pp_ = (Mat2::Identity() - J) * Pp_;
    Pp_ = 0.5 * (Pp_ + Pp_.transpose()).eval();
    d.accepted = true;
    d.reason = std::isfinite(gate2_) ? "accepted" : "ungated";
  }

  void inflateHeading() override {
    Pth_ = std::max(Pth_, std::min(Pth_ * cfg_.lockout_inflation, kLockoutMaxHeadingStd * kLockoutMaxHeadingStd));
  }
  void inflatePosition() override {
    detail::inflateCapped(Pp_, {{0, cfg_.lockout_max_std}, {1, cfg_.lockout_max_std}}, cfg_.lockout_inflation);
  }
  void growPosition(double dt) override {
    Pp_.diagonal().array() += g_.position_rw * g_.position_rw * dt;
  }

 private:
  Vec2 p_;
  Mat2 Pp_;
  double th_ = 0, Pth_ = 0;
  Vec2 sv_;   ///< [s, v]
  Mat2 Psv_;
};

// ---------------------------------------------------------------------------------------------
/// A UKF over the same sensors and the same models (gnss_model.hpp), with the full 5x5
/// covariance: GPS fixes then also correct heading and speed through their correlations.
/// The encoder distance is an ungated 1-D update (a gate on an accumulated distance would
/// reject every later sample after one slip); magnetometer heading and GPS are gated.
class GpsUkf final : public GnssFilterBase {
  using U = Ukf<kN>;

 public:
  explicit GpsUkf(const FilterConfig& c) : GnssFilterBase(c), ukf_(c.sigma, 1u << kTheta) {
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(x, P);
    setState(x, P);
  }
  const std::string& name() const override {
    static const std::string n = "ukf_gps";
    return n;
  }
  double heading() const override { return ukf_.x()[kTheta]; }

 protected:
  void fillState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const override {
    x = ukf_.x();
    P = ukf_.P();
  }
  void setState(const Eigen::VectorXd& x, const Eigen::MatrixXd& P) override {
    ukf_.reset(x, P);
  }

  void timeUpdate(const Step& st) override {
    const double L = cfg_.wheelbase;
    auto f = [&st, L](const U::Vector& s) {
      U::Vector o;
      const double v = s[kSpeed];
      o.head<2>() = gnss::positionStep(s.head<2>(), v, s[kTheta], st.T);
      o[kTheta] = wrapAngle(s[kTheta] + (st.has_steering ? st.T * gnss::headingRate(v, st.psi, L)
                                                         : st.delta_theta));
      const Vec2 sv = gnss::kinematicStep(Vec2(s[kDistance], v), st.a, st.T);
      o[kDistance] = sv[0];
      o[kSpeed] = sv[1];
      return o;
    };
    U::Matrix Q = U::Matrix::Zero();
    Q(kX, kX) = Q(kY, kY) = g_.position_rw * g_.position_rw * st.T;
    // Steering noise and heading random walk (the speed's share comes from the sigma points).
    Step no_speed = st;
    Q(kTheta, kTheta) = headingNoise(no_speed, ukf_.x()[kSpeed], 0.0);
    const Vec2 B = gnss::kinematicB(st.T);
    const Mat2 Qsv = B * B.transpose() * (st.a_std * st.a_std);
    Q(kDistance, kDistance) = Qsv(0, 0);
    Q(kDistance, kSpeed) = Q(kSpeed, kDistance) = Qsv(0, 1);
    Q(kSpeed, kSpeed) = Qsv(1, 1);
    if (!ukf_.predict(f, Q)) return;
    Innovation<kN, 1> in;
    const Eigen::Matrix<double, 1, 1> R = Eigen::Matrix<double, 1, 1>::Constant(
        g_.encoder_std * g_.encoder_std);
    const Eigen::Matrix<double, 1, 1> z = Eigen::Matrix<double, 1, 1>::Constant(enc_sum_);
    if (ukf_.innovate<1>([](const U::Vector& s) { return Eigen::Matrix<double, 1, 1>(s[kDistance]); },
                         R, z, 0u, in))
      ukf_.correct(in);
  }

  void headingUpdate(double zth, double r, GateDecision& d) override {
    Innovation<kN, 1> in;
    const Eigen::Matrix<double, 1, 1> R = Eigen::Matrix<double, 1, 1>::Constant(r);
    const Eigen::Matrix<double, 1, 1> z = Eigen::Matrix<double, 1, 1>::Constant(zth);
    if (!ukf_.innovate<1>([](const U::Vector& s) { return Eigen::Matrix<double, 1, 1>(s[kTheta]); },
                          R, z, 1u, in)) {
      d.reason = "bad_input";
      return;
    }
    apply(in, gate1_, d);
  }

  void positionUpdate(const Vec2& zp, double r, GateDecision& d) override {
    Innovation<kN, 2> in;
    const Mat2 R = r * Mat2::Identity();
    if (!ukf_.innovate<2>([](const U::Vector& s) { return Vec2(s.head<2>()); }, R, zp, 0u, in)) {
      d.reason = "bad_input";
      return;
    }
    apply(in, gate2_, d);
  }

  void inflateHeading() override { inflateStates({{kTheta, kLockoutMaxHeadingStd}}); }
  void inflatePosition() override { inflateStates({{kX, cfg_.lockout_max_std}, {kY, cfg_.lockout_max_std}}); }
  void growPosition(double dt) override {
    U::Matrix P = ukf_.P();
    P(kX, kX) += g_.position_rw * g_.position_rw * dt;
    P(kY, kY) += g_.position_rw * g_.position_rw * dt;
    ukf_.reset(ukf_.x(), P);
  }

 private:
  template <int M>
  void apply(const Innovation<kN, M>& in, double gate, GateDecision& d) {
    d.innovation = in.v;
    d.mahalanobis = in.mahalanobis;
    if (!(in.mahalanobis <= gate)) {
      d.reason = "gate";
      return;
    }
    ukf_.correct(in);
    d.accepted = true;
    d.reason = std::isfinite(gate) ? "accepted" : "ungated";
  }
  void inflateStates(std::initializer_list<detail::InflateCap> states) {
    U::Matrix P = ukf_.P();
    detail::inflateCapped(P, states, cfg_.lockout_inflation);
    ukf_.reset(ukf_.x(), P);
  }

  U ukf_;
};

}  // namespace

std::unique_ptr<Filter> detail::makeGnssFilter(const FilterConfig& cfg) {
  if (cfg.type != "tvekf" && cfg.type != "ukf_gps") return nullptr;
  validateGnss(cfg);
  if (cfg.type == "tvekf") return std::make_unique<TvEkf>(cfg);
  return std::make_unique<GpsUkf>(cfg);
}

}  // namespace lcmloc::core
