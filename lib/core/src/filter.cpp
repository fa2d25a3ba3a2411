// What every filter shares (filter.hpp): the configuration's checks, the state checks, the hot
// swap, lock-out caps, the pose fix and the one factory. The filters are in ruler_filters.cpp
// (dead_reckoning, ukf, ukf_gated, ukf_calib), gnss_filters.cpp (tvekf, ukf_gps),
// landmark_filters.cpp (ukf_landmarks) and odo_ins_filter.cpp (odo_ins, odo_ins_uncal).
#include "lcmloc/core/filter.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include <Eigen/Eigenvalues>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/chi2.hpp"
#include "filter_internal.hpp"

namespace lcmloc::core {

double GateConfig::threshold(int innovation_dim) const {
  if (value) return *value;
  return chi2Quantile(probability, dof > 0 ? dof : innovation_dim);
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("filter config: " + what);
}

void validate(const FilterConfig& c) {
  require(std::isfinite(c.wheelbase) && c.wheelbase > 0, "wheelbase must be > 0");
  require(std::isfinite(c.ruler_offset) && c.ruler_offset > 0, "ruler_offset must be > 0");
  require(std::isfinite(c.ruler_half_width) && c.ruler_half_width > 0,
          "ruler_half_width must be > 0");
  require(c.initial_pose.allFinite(), "initial_pose must be finite");
  require(c.p0_diag.allFinite() && (c.p0_diag.array() > 0).all(), "p0_diag must be > 0");
  require(c.pw_diag.allFinite() && (c.pw_diag.array() >= 0).all(), "pw_diag must be >= 0");
  require(std::isfinite(c.pw_distance) && c.pw_distance >= 0, "pw_distance must be >= 0");
  require(c.pv_diag.allFinite() && (c.pv_diag.array() > 0).all(), "pv_diag must be > 0");
  require(std::isfinite(c.sigma.alpha) && c.sigma.alpha > 0, "sigma.alpha must be > 0");
  require(std::isfinite(c.sigma.beta) && std::isfinite(c.sigma.kappa), "sigma must be finite");
  require(c.sigma.alpha * c.sigma.alpha * (3.0 + c.sigma.kappa) > 0,
          "sigma: alpha^2 (n + kappa) must be > 0");
  if (c.gate.value)
    require(std::isfinite(*c.gate.value) && *c.gate.value > 0, "gate.value must be > 0");
  require(c.gate.probability > 0 && c.gate.probability < 1, "gate.probability must be in (0, 1)");
  require(c.gate.dof >= 0 && c.gate.dof <= 10, "gate.dof must be in 0..10");
  require(std::isfinite(c.reach_forward) && c.reach_forward >= 0, "reach_forward must be >= 0");
  require(std::isfinite(c.reach_lateral) && c.reach_lateral >= 0, "reach_lateral must be >= 0");
  require(c.lockout_rejections >= 0, "lockout_rejections must be >= 0");
  require(std::isfinite(c.lockout_inflation) && c.lockout_inflation >= 1,
          "lockout_inflation must be >= 1");
  require(std::isfinite(c.lockout_max_std) && c.lockout_max_std > 0, "lockout_max_std must be > 0");
  require(std::isfinite(c.scale_std0) && c.scale_std0 > 0, "scale_std0 must be > 0");
  require(std::isfinite(c.steer_bias_std0) && c.steer_bias_std0 > 0,
          "steer_bias_std0 must be > 0");
  require(std::isfinite(c.scale_rw) && c.scale_rw >= 0, "scale_rw must be >= 0");
  require(std::isfinite(c.steer_bias_rw) && c.steer_bias_rw >= 0, "steer_bias_rw must be >= 0");
  require(std::isfinite(c.pw_turn) && c.pw_turn >= 0, "pw_turn must be >= 0");
  require(std::isfinite(c.landmarks.range_std) && c.landmarks.range_std > 0, "landmarks.range_std must be > 0");
  require(std::isfinite(c.landmarks.bearing_std) && c.landmarks.bearing_std > 0,
          "landmarks.bearing_std must be > 0");
  require(std::isfinite(c.landmarks.beacon_std) && c.landmarks.beacon_std > 0, "landmarks.beacon_std must be > 0");
  require(std::isfinite(c.landmarks.correlation_factor) && c.landmarks.correlation_factor >= 1,
          "landmarks.correlation_factor must be >= 1");
  const auto& k = c.calibration;
  for (const auto& [std0, name] : {std::pair{k.beacon_bias_std, "beacon_bias_std"}, {k.odo_scale_std, "odo_scale_std"},
                                   {k.yaw_rate_scale_std, "yaw_rate_scale_std"}, {k.yaw_rate_bias_std, "yaw_rate_bias_std"},
                                   {k.steering_bias_std, "steering_bias_std"}, {k.mag_bias_std, "mag_bias_std"},
                                   {k.mag_bias_tau, "mag_bias_tau"}, {k.accel_bias_std, "accel_bias_std"}})
    require(std::isfinite(std0) && std0 > 0, std::string("calibration.") + name + " must be > 0");
  for (const auto& [rw, name] : {std::pair{k.beacon_bias_rw, "beacon_bias_rw"}, {k.odo_scale_rw, "odo_scale_rw"},
                                 {k.yaw_rate_scale_rw, "yaw_rate_scale_rw"}, {k.yaw_rate_bias_rw, "yaw_rate_bias_rw"},
                                 {k.steering_bias_rw, "steering_bias_rw"}, {k.accel_bias_rw, "accel_bias_rw"}})
    require(std::isfinite(rw) && rw >= 0, std::string("calibration.") + name + " must be >= 0");
  for (const auto& [mean, name] : {std::pair{k.beacon_bias_mean, "beacon_bias_mean"}, {k.odo_scale_mean, "odo_scale_mean"},
                                   {k.yaw_rate_scale_mean, "yaw_rate_scale_mean"}, {k.yaw_rate_bias_mean, "yaw_rate_bias_mean"},
                                   {k.steering_bias_mean, "steering_bias_mean"}})
    require(std::isfinite(mean), std::string("calibration.") + name + " must be finite");
  // A filter with calibration states of its own refuses a switch for a state it does not have
  // (the switch would be ignored, the user believing the bias estimated).
  const bool landmarks = c.type == "ukf_landmarks", gnss = isGnssFilter(c.type);
  for (const auto& [on, name, ok] :
       {std::tuple{k.beacon_bias != FilterConfig::Calibration::BeaconBias::Off, "beacon_bias", landmarks},
        {k.yaw_rate_scale, "yaw_rate_scale", landmarks}, {k.yaw_rate_bias, "yaw_rate_bias", landmarks},
        {k.steering_bias, "steering_bias", gnss}, {k.mag_bias, "mag_bias", gnss},
        {k.accel_bias, "accel_bias", gnss}})
    require(!on || ok || !(landmarks || gnss),
            std::string("calibration.") + name + " is not a state of " + c.type + " (its states: " +
                (landmarks ? "beacon_bias, odo_scale, yaw_rate_scale, yaw_rate_bias"
                           : "odo_scale, steering_bias, mag_bias, accel_bias") +
                ")");
}

}  // namespace

/// Pose process noise of one step: Pw accumulated over pw_distance metres of travel
/// (per step as printed when pw_distance = 0). See docs/paper_000_reading.md.
/// Plus pw_turn |dtheta| on the heading, so that turning in place is not noise-free.
Vec3 detail::poseProcessNoise(const FilterConfig& c, double ds, double dtheta) {
  Vec3 q = c.pw_distance > 0 ? Vec3(c.pw_diag * (std::abs(ds) / c.pw_distance)) : c.pw_diag;
  q[2] += c.pw_turn * std::abs(dtheta);
  return q;
}

std::vector<detail::InflateCap> detail::lockoutCaps(const FilterConfig& cfg, const std::vector<std::string>& names) {
  std::vector<InflateCap> caps;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    const double cap = n == "x" || n == "y"  ? cfg.lockout_max_std
                       : n == "theta"        ? kLockoutMaxHeadingStd
                       : n == "odo_scale"    ? cfg.scale_std0
                       : n == "steer_bias"   ? cfg.steer_bias_std0
                                             : 0.0;  // (no other state is inflated)
    caps.push_back({static_cast<int>(i), cap});
  }
  return caps;
}

std::string unusableState(const FilterState& s) {
  const auto n = s.x.size();
  if (n < 3 || s.P.rows() != n || s.P.cols() != n) return "state must have >= 3 entries and a matching P";
  if (!s.x.allFinite() || !s.P.allFinite()) return "state or covariance not finite";
  if (std::abs(s.x(0)) > kMaxAbsPosition || std::abs(s.x(1)) > kMaxAbsPosition) {
    std::ostringstream o;
    o << std::setprecision(6) << "position (" << s.x(0) << ", " << s.x(1) << ") m is beyond " << kMaxAbsPosition << " m";
    return o.str();
  }
  if (s.P.diagonal().maxCoeff() > kMaxVariance) {
    std::ostringstream o;
    o << std::setprecision(6) << "a variance (" << s.P.diagonal().maxCoeff() << ") is beyond " << kMaxVariance;
    return o.str();
  }
  for (int i = 0; i < 3; ++i)
    if (!(s.P(i, i) > 0.0)) return "the variance of " + std::string(i == 0 ? "x" : i == 1 ? "y" : "theta") + " is not > 0";
  const double scale = s.P.diagonal().cwiseAbs().maxCoeff();
  if (!(s.P - s.P.transpose()).isZero(1e-9 * scale)) return "covariance not symmetric";
  const double min_eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s.P, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
  if (min_eig < -1e-9 * scale) return "covariance not positive semi-definite (an eigenvalue is " + std::to_string(min_eig) + ")";
  return "";
}

/// Hot swap: starts from the filter's initial values and copies every state of `from` that has
/// the same name (x, y, theta always: a source without names is read as x, y, theta, ...),
/// with the covariance among copied states; cross-covariances to other states are zero.
void detail::copyMatching(const FilterState& from, const std::vector<std::string>& names,
                  Eigen::VectorXd& x, Eigen::MatrixXd& P) {
  const auto n_from = from.x.size();
  if (const std::string why = unusableState(from); !why.empty()) throw std::invalid_argument("initialize: " + why);
  const bool named = static_cast<Eigen::Index>(from.names.size()) == n_from;
  std::vector<int> src(names.size(), -1);
  for (size_t i = 0; i < names.size(); ++i) {
    if (i < 3) { src[i] = static_cast<int>(i); continue; }
    for (Eigen::Index j = 3; named && j < n_from; ++j)
      if (from.names[j] == names[i]) src[i] = static_cast<int>(j);
  }
  for (size_t i = 0; i < names.size(); ++i) {
    if (src[i] < 0) continue;
    x[i] = from.x[src[i]];
    for (size_t j = 0; j < names.size(); ++j) {
      if (src[j] < 0) continue;
      P(i, j) = from.P(src[i], src[j]);
    }
    for (size_t j = 0; j < names.size(); ++j)
      if (src[j] < 0) P(i, j) = P(j, i) = 0.0;
  }
  x[2] = wrapAngle(x[2]);
}

GateDecision Filter::update(const RulerDetection& det) {
  GateDecision d = detail::decision(det.utime, det.sensor, det.seq, kInf);
  d.reason = "ignored";
  return d;
}

bool isGnssFilter(const std::string& type) { return type == "tvekf" || type == "ukf_gps"; }

std::vector<std::string> filterTypes() {
  return {"dead_reckoning", "ukf", "ukf_gated", "ukf_calib", "tvekf", "ukf_gps", "ukf_landmarks", "odo_ins",
          "odo_ins_uncal"};
}

std::string filterTypeList() {
  std::string s;
  for (const auto& t : filterTypes()) s += (s.empty() ? "" : ", ") + t;
  return s;
}

bool Filter::applyFix(const PoseFix& fix) {
  if (!detail::usableFix(fix)) return false;
  FilterState s = state();
  s.utime = std::max(s.utime, fix.utime);
  s.x.head<3>() = fix.pose;
  s.x[2] = wrapAngle(s.x[2]);
  s.P.topRows<3>().setZero();
  s.P.leftCols<3>().setZero();
  s.P.topLeftCorner<3, 3>() = 0.5 * (fix.cov + fix.cov.transpose());
  initialize(s);
  return true;
}

std::unique_ptr<Filter> makeFilter(const FilterConfig& cfg, const MarkerMap& map) {
  return makeFilterOver(cfg, std::make_shared<const MapIndex>(map));
}

std::unique_ptr<Filter> makeFilterOver(const FilterConfig& cfg, const SharedMapIndex& map) {
  validate(cfg);
  if (auto f = detail::makeRulerFilter(cfg, map)) return f;
  if (auto f = detail::makeGnssFilter(cfg)) return f;
  if (auto f = detail::makeLandmarkFilter(cfg, map)) return f;
  if (auto f = detail::makeOdoInsFilter(cfg)) return f;
  throw std::invalid_argument("filter config: unknown type '" + cfg.type + "' (known: " + filterTypeList() + ")");
}

}  // namespace lcmloc::core
