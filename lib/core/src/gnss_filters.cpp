// The GNSS filters: the time-varying EKF of Choi and Kong (seeds/002, "tvekf") and a UKF over
// the same sensors ("ukf_gps"). Both: state (x, y, theta, speed, distance); odometry (encoder
// distance + steering) drives the time update together with the forward acceleration of the
// IMU; the magnetometer heading and GPS fixes are measurements, each behind a chi-square gate,
// each with its own lock-out detector. Derivations and measured results: docs/tvekf.md.
// Here: what both share (declared in gnss_filter_base.hpp), the configuration's checks and the
// factory; the filters themselves are in tvekf_filter.cpp and gps_ukf_filter.cpp.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "gnss_filter_base.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/gnss_model.hpp"

namespace lcmloc::core {
namespace gnss_filter {

using detail::decision;

GnssCalibration GnssCalibration::of(const FilterConfig& c) {
  GnssCalibration l;
  l.cfg = c.calibration;
  l.names = {"x", "y", "theta", "speed", "distance"};
  std::vector<double> x0(kN, 0.0), p0(kN, 0.0);
  auto add = [&](const char* name, double mean, double std0) {
    l.names.push_back(name);
    x0.push_back(mean);
    p0.push_back(std0 * std0);
    return l.size() - 1;
  };
  const auto& k = c.calibration;
  if (k.odo_scale) l.odo_scale = add("cal_odo_scale", k.odo_scale_mean, k.odo_scale_std);
  if (k.steering_bias) l.steering_bias = add("cal_steering_bias", k.steering_bias_mean, k.steering_bias_std);
  if (k.mag_bias) l.mag_bias = add("cal_mag_bias", 0.0, k.mag_bias_std);
  if (k.accel_bias) l.accel_bias = add("cal_accel_bias", 0.0, k.accel_bias_std);
  l.x0 = Eigen::Map<const Eigen::VectorXd>(x0.data(), static_cast<Eigen::Index>(x0.size()));
  l.p0 = Eigen::Map<const Eigen::VectorXd>(p0.data(), static_cast<Eigen::Index>(p0.size()));
  return l;
}

void GnssFilterBase::initialize(const FilterState& from) {
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
  rejected_.clear();
  confirmed_ = false;
  relocalized_.reset();
  gps_lock_ = Lockout(g_.gps_lockout_rejections);
  mag_lock_ = Lockout(g_.mag_lockout_rejections);
}

void GnssFilterBase::predict(const OdometryInput& odo) {
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
    st.has_accel = false;
  }
  acc_sum_ = 0;
  acc_n_ = 0;
  st.has_steering = odo.has_steering;
  st.psi = odo.steering;
  st.delta_theta = odo.delta_theta;
  timeUpdate(st);
  last_position_utime_ = std::max(last_position_utime_, odo.utime);
  if (!rejected_.empty()) {  // the dead-reckoned motion that carries the refused fixes forward
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    fillState(x, P);
    rejected_.move(odo.delta_s, heading(), headingNoise(st, x[kSpeed], P(kSpeed, kSpeed)));
  }
  if (course_open_) {  // dead-reckoned displacement along the filter's heading since the anchor fix
    const double th = heading();
    course_dr_ += odo.delta_s * Vec2(std::cos(th), std::sin(th));
    course_dist_ += std::abs(odo.delta_s);
  }
}

std::optional<GateDecision> GnssFilterBase::update(const ImuInput& m) {
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
  headingUpdate(z, g_.mag_std * g_.mag_std, d, true);
  if (d.reason == "gate" && mag_lock_.reject()) inflateHeading();
  if (d.accepted) mag_lock_.accept();
  return d;
}

std::optional<GateDecision> GnssFilterBase::update(const GpsInput& gps) {
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
  const Vec2 z(gps.x, gps.y);
  positionUpdate(z, sd * sd, d);
  if (d.reason == "gate") {
    refusedFix(gps, z, sd, d);
  } else if (d.accepted) {
    gps_lock_.accept();
    rejected_.clear();
    confirmed_ = true;
    have_fix_ = true;
    last_fix_utime_ = gps.utime;
    if (use_course_ && g_.course_distance > 0) courseAid(z, sd);
  }
  return d;
}

void GnssFilterBase::initialState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const {
  x = cal_.x0;
  P = Eigen::MatrixXd(cal_.p0.asDiagonal());
  x.head<3>() = cfg_.initial_pose;
  x[kTheta] = wrapAngle(x[kTheta]);
  P.topLeftCorner<3, 3>() = cfg_.p0_diag.asDiagonal();
  P(kSpeed, kSpeed) = g_.speed_std0 * g_.speed_std0;
  P(kDistance, kDistance) = g_.encoder_std * g_.encoder_std;
}

FilterStatus GnssFilterBase::status() const {
  if (gps_lock_.active() || mag_lock_.active()) return FilterStatus::Lockout;
  const auto timeout = static_cast<int64_t>(g_.coast_timeout * 1e6);
  if (!have_fix_ || utime_ - last_fix_utime_ > timeout) return FilterStatus::DeadReckoning;
  return FilterStatus::Ok;
}

double GnssFilterBase::headingNoise(const Step& st, double v, double Pv) const {
  double q = g_.heading_rw * g_.heading_rw * st.T;
  if (st.has_steering) {
    const double c = std::cos(st.psi), t = std::tan(st.psi), L = cfg_.wheelbase;
    const double dv = st.T * t / L, dpsi = st.T * v / (L * c * c);
    q += dv * dv * Pv + dpsi * dpsi * g_.steering_std * g_.steering_std;
  }
  return q;
}

double GnssFilterBase::headingIncrement(const Step& st, double v) const {
  return st.has_steering ? st.T * gnss::headingRate(v, st.psi, cfg_.wheelbase) : st.delta_theta;
}

void GnssFilterBase::courseAid(const Vec2& z, double sd) {
  if (!course_open_ || course_dist_ >= g_.course_distance) {
    if (course_open_) {
      const Vec2 c = z - course_anchor_;
      // a chord much shorter than the travel (a U-turn, reversing back and forth) says little
      if (c.norm() >= 0.5 * course_dist_ && course_dr_.norm() >= 0.5 * course_dist_) {
        const double err = wrapAngle(std::atan2(c.y(), c.x()) - std::atan2(course_dr_.y(), course_dr_.x()));
        const double r = 2.0 * sd * sd / c.squaredNorm() + g_.course_std * g_.course_std;
        GateDecision d = decision(last_fix_utime_, "GPS_COURSE", 0, gate1_);
        headingUpdate(wrapAngle(heading() + err), r, d, false);
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

}  // namespace gnss_filter

namespace {

using gnss_filter::kN;

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

}  // namespace

std::unique_ptr<Filter> detail::makeGnssFilter(const FilterConfig& cfg) {
  if (!isGnssFilter(cfg.type)) return nullptr;
  validateGnss(cfg);
  if (cfg.type == "tvekf") return gnss_filter::makeTvEkf(cfg);
  return gnss_filter::makeGpsUkf(cfg);
}

}  // namespace lcmloc::core
