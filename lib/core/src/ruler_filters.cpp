// The filters of the magnetic-ruler method: "dead_reckoning" (odometry only, eq. 1-2) and the
// UKF of §3.2 over the ruler's detections, "ukf", "ukf_gated" (with the chi-square gate of §3.3)
// and "ukf_calib" (with the odometer scale and steering bias states). See
// docs/paper_000_reading.md.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "filter_internal.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/odometry_batch.hpp"
#include "lcmloc/core/ruler_model.hpp"
#include "lcmloc/core/vehicle_model.hpp"

namespace lcmloc::core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr AngleMask kThetaMask = 1u << 2;    // state: x, y, theta, ...
constexpr AngleMask kBearingMask = 1u << 1;  // measurement: range, bearing

bool isFinite(const OdometryInput& o) {
  return std::isfinite(o.delta_s) && (o.has_steering ? std::isfinite(o.steering)
                                                     : std::isfinite(o.delta_theta));
}

using detail::copyMatching;
using detail::poseProcessNoise;

/// Composes one increment of eq. 1-2 and its process noise into a batch (a non-finite one is
/// skipped, as predict() skips it).
void addToBatch(const FilterConfig& c, const OdometryInput& odo, OdometryBatch& batch, TanCache& tan) {
  if (!isFinite(odo)) return;
  const double dth = headingIncrement(odo, c.wheelbase, tan);
  batch.add(odo.delta_s, dth, odo.utime, poseProcessNoise(c, odo.delta_s, dth));
}

/// The odometry increments a batching filter took since its last time update
/// (Filter::accumulate), composed into an OdometryBatch in one loop: when the update comes, or
/// every kFold steps (so that a long batch, fusion.output_every up to a million, holds no more
/// than kFold steps). The work of a step that does not depend on the step before (eq. 2's
/// tangent, the half-angle sine and cosine, the process noise) then overlaps with the steps
/// around it, which it cannot while each step comes between the daemon's work for one message
/// and the next. The same operations in the same order as composing each step when it comes:
/// the same numbers. eq. 2's tangent comes from the filter's TanCache (the one its predict()
/// uses).
class PendingOdometry {
 public:
  void add(const FilterConfig& c, const OdometryInput& odo, TanCache& tan) {
    steps_.push_back(odo);
    if (steps_.size() == kFold) fold(c, tan);
  }
  bool empty() const { return steps_.empty() && batch_.empty(); }
  void clear() {
    steps_.clear();
    batch_.clear();
  }
  /// The batch of the steps since the last one (non-finite ones skipped); the next add starts
  /// a new batch.
  OdometryBatch compose(const FilterConfig& c, TanCache& tan) {
    fold(c, tan);
    OdometryBatch b = batch_;
    batch_.clear();
    return b;
  }

 private:
  static constexpr std::size_t kFold = 64;
  void fold(const FilterConfig& c, TanCache& tan) {
    for (const OdometryInput& odo : steps_) addToBatch(c, odo, batch_, tan);
    steps_.clear();
  }
  std::vector<OdometryInput> steps_;
  OdometryBatch batch_;
};

/// Initial state and covariance of a filter with these state names.
void initialState(const FilterConfig& c, const std::vector<std::string>& names,
                  Eigen::VectorXd& x, Eigen::MatrixXd& P) {
  const int n = static_cast<int>(names.size());
  x = Eigen::VectorXd::Zero(n);
  P = Eigen::MatrixXd::Zero(n, n);
  x.head<3>() = c.initial_pose;
  x[2] = wrapAngle(x[2]);
  P.topLeftCorner<3, 3>() = c.p0_diag.asDiagonal();
  for (int i = 3; i < n; ++i)
    P(i, i) = names[i] == "odo_scale" ? c.scale_std0 * c.scale_std0
                                      : c.steer_bias_std0 * c.steer_bias_std0;
}

GateDecision makeDecision(const RulerDetection& det, double gate) {
  return detail::decision(det.utime, det.sensor, det.seq, gate);
}

// ---------------------------------------------------------------------------------------------
/// Odometry only (eq. 1-2); covariance propagated by linearisation with the same process noise.
class DeadReckoningFilter final : public Filter {
 public:
  explicit DeadReckoningFilter(const FilterConfig& c) : cfg_(c) {
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(cfg_, names_, x, P);
    x_ = x;
    P_ = P;
  }
  const std::string& name() const override {
    static const std::string n = "dead_reckoning";
    return n;
  }
  void stateInto(FilterState& s) const override {
    s.utime = utime_;
    s.x = x_;
    s.P = P_;
    detail::setNames(s, names_);
    s.status = FilterStatus::DeadReckoning;
  }
  FilterStatus status() const override { return FilterStatus::DeadReckoning; }
  void initialize(const FilterState& from) override {
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(cfg_, names_, x, P);
    copyMatching(from, names_, x, P);
    x_ = x;
    P_ = P;
    utime_ = from.utime;
    pending_.clear();
  }
  bool accumulate(const OdometryInput& odo) override {
    pending_.add(cfg_, odo, tan_);
    return true;
  }
  /// The Jacobians of eq. 1 are I + [0 0 -dy_k; 0 0 dx_k; 0 0 0] (world displacement of step k):
  /// their product over the batch is the same form with the batch's world displacement, exact.
  void applyAccumulated() override {
    if (pending_.empty()) return;
    const OdometryBatch batch = pending_.compose(cfg_, tan_);
    if (batch.empty()) return;
    const SinCosNear h(x_.z());
    const double c = h.c, s = h.s;
    Mat3 F = Mat3::Identity();
    F(0, 2) = -s * batch.dx - c * batch.dy;
    F(1, 2) = c * batch.dx - s * batch.dy;
    const Mat3 Q = batch.noise(h);
    x_ = batch.apply(x_, h);
    P_ = F * P_ * F.transpose() + Q;
    utime_ = batch.utime;
  }
  void predict(const OdometryInput& odo) override {
    if (!isFinite(odo)) return;
    const double ds = odo.delta_s, dth = headingIncrement(odo, cfg_.wheelbase, tan_);
    const double mid = x_.z() + 0.5 * dth;
    Mat3 F = Mat3::Identity();
    F(0, 2) = -ds * std::sin(mid);
    F(1, 2) = ds * std::cos(mid);
    x_ = propagatePose(x_, ds, dth);
    P_ = F * P_ * F.transpose();
    P_.diagonal() += poseProcessNoise(cfg_, ds, dth);
    utime_ = odo.utime;
  }
  GateDecision update(const RulerDetection& det) override {
    GateDecision d = makeDecision(det, kInf);
    d.reason = std::isfinite(det.lateral_offset) ? "dead_reckoning" : "bad_input";
    return d;
  }

 protected:
  void addPoseNoise(const Mat3& Q) override { P_ += Q; }  // (always DeadReckoning)

 private:
  FilterConfig cfg_;
  std::vector<std::string> names_{"x", "y", "theta"};
  Vec3 x_;
  Mat3 P_;
  int64_t utime_ = 0;
  PendingOdometry pending_;
  TanCache tan_;  ///< eq. 2's tangent, for predict() and the batch
};

// ---------------------------------------------------------------------------------------------
/// The UKF of §3.2 with the range-bearing ruler measurement (eq. 3-6), association restricted to
/// markers the ruler can reach, optional chi-square gate (§3.3) and lock-out detection.
/// N = 3: (x, y, theta). N = 5: + odometer scale error k and steering bias b (online calibration).
template <int N>
class RulerUkf final : public Filter {
  using U = Ukf<N>;

 public:
  RulerUkf(std::string name, const FilterConfig& c, SharedMapIndex map, bool gated)
      : name_(std::move(name)), cfg_(c), map_(std::move(map)), gated_(gated && c.gate.enabled),
        gate_(gated_ ? c.gate.threshold(2) : kInf), ukf_(c.sigma, kThetaMask) {
    names_ = {"x", "y", "theta"};
    if (N == 5) names_.insert(names_.end(), {"odo_scale", "steer_bias"});
    book_.caps = detail::lockoutCaps(cfg_, names_);
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(cfg_, names_, x, P);
    ukf_.reset(x, P);
    R_ = cfg_.pv_diag.asDiagonal();
    const double f = std::abs(cfg_.ruler_offset) + cfg_.reach_forward;
    const double l = cfg_.ruler_half_width + cfg_.reach_lateral;
    reach_radius_ = std::sqrt(f * f + l * l) * (1.0 + 1e-9);
  }

  const std::string& name() const override { return name_; }

  void stateInto(FilterState& s) const override {
    s.utime = utime_;
    s.x = ukf_.x();
    s.P = ukf_.P();
    detail::setNames(s, names_);
    s.status = book_.status;
  }
  FilterStatus status() const override { return book_.status; }

  void initialize(const FilterState& from) override {
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(cfg_, names_, x, P);
    copyMatching(from, names_, x, P);
    ukf_.reset(x, P);
    utime_ = from.utime;
    book_.reset();
    pending_.clear();
  }

  /// Batching needs a process model that does not depend on the state: (x, y, theta) only.
  bool accumulate(const OdometryInput& odo) override {
    if constexpr (N != 3) {
      return false;
    } else {
      pending_.add(cfg_, odo, tan_);
      return true;
    }
  }
  /// One time update with the composed increment (the same mean as the steps one by one) and
  /// the process noise of the steps as the remaining steps carry it (linearised at the mean).
  void applyAccumulated() override {
    if (pending_.empty()) return;
    const OdometryBatch b = pending_.compose(cfg_, tan_);
    if (b.empty()) return;
    const SinCosNear mean(ukf_.x()(2));  // the sigma points' headings lie around it
    auto f = [&b, &mean](const typename U::Vector& s) {
      typename U::Vector out = s;
      out.template head<3>() = b.apply(s.template head<3>(), mean);
      return out;
    };
    typename U::Matrix Q = U::Matrix::Zero();
    Q.template topLeftCorner<3, 3>() = b.noise(mean);
    if (ukf_.predict(f, Q)) utime_ = b.utime;
  }

  void predict(const OdometryInput& odo) override {
    if (!isFinite(odo)) return;
    const double L = cfg_.wheelbase;
    // eq. 1-2; with N = 5 the increments are corrected by the calibration states.
    const double dth_meas = headingIncrement(odo, L, tan_);
    const SinCosNear mid(ukf_.x()(2) + 0.5 * dth_meas);  // the sigma points' midpoint headings lie around it
    auto f = [&odo, L, dth_meas, &mid](const typename U::Vector& s) {
      typename U::Vector out = s;
      double ds = odo.delta_s, dth = dth_meas;
      if constexpr (N == 5) {
        ds *= 1.0 + s[3];
        if (odo.has_steering) dth = headingIncrement(ds, odo.steering - s[4], L);
      }
      out.template head<3>() = propagatePose(s.template head<3>(), ds, dth, mid);
      return out;
    };
    typename U::Matrix Q = U::Matrix::Zero();
    Q.template topLeftCorner<3, 3>().diagonal() = poseProcessNoise(cfg_, odo.delta_s, dth_meas);
    if constexpr (N == 5) {
      Q(3, 3) = cfg_.scale_rw * cfg_.scale_rw * std::abs(odo.delta_s);
      Q(4, 4) = cfg_.steer_bias_rw * cfg_.steer_bias_rw * std::abs(odo.delta_s);
    }
    if (ukf_.predict(f, Q)) utime_ = odo.utime;
  }

  GateDecision update(const RulerDetection& det) override {
    GateDecision d = makeDecision(det, gate_);
    typename U::Sigmas X;
    if (!std::isfinite(det.lateral_offset) || !std::isfinite(det.quality) ||
        !ukf_.sigmaPoints(X)) {
      d.reason = "bad_input";
      return d;
    }
    Vec2 z = rulerObservation(det.lateral_offset, cfg_.ruler_offset);
    const Pose pose = ukf_.x().template head<3>();
    Innovation<N, 2> best, cand;
    int best_id = -1;
    const double margin = reachMargin();
    // While the ruler's position is known to well within L1 (tracking), the range-bearing model
    // of eq. 3-6. When its 3-sigma spread exceeds L1 after an odometry gap (status DeadReckoning
    // until a detection is accepted), the sigma points lie on both sides of the marker and the
    // range folds: the marker's position in the body frame (forward, left), linear in the
    // position, with the range-bearing noise carried into it, instead. (Not after a lock-out
    // inflation: the lock-out's re-acquisition is as it was.)
    const bool wide = book_.status == FilterStatus::DeadReckoning && margin > cfg_.ruler_offset;
    Mat2 R = R_;
    if (wide) {
      const double r = z[0], c = std::cos(z[1]), sn = std::sin(z[1]);
      Mat2 J;
      J << c, -r * sn, sn, r * c;
      R = J * R_ * J.transpose();
      z = Vec2(r * c, r * sn);
    }
    // the markers within the reachable window's radius (reachable()'s pre-test), in map order
    const double radius = reach_radius_ + M_SQRT2 * margin;
    map_->near(pose.x(), pose.y(), MapIndex::widen(radius, pose.x(), pose.y()), near_);
    for (const uint32_t i : near_) {
      const Marker& m = (*map_)[i];
      if (!reachable(pose, m, margin)) continue;
      auto h = [&m, wide](const typename U::Vector& s) {
        return wide ? markerInBody(s.template head<3>(), m.x, m.y)
                    : predictRangeBearing(s.template head<3>(), m.x, m.y);
      };
      if (!ukf_.template innovate<2>(X, h, R, z, wide ? AngleMask{0} : kBearingMask, cand)) continue;
      if (best_id < 0 || cand.mahalanobis < best.mahalanobis) {
        best = cand;
        best_id = m.id;
      }
    }
    utime_ = std::max(utime_, det.utime);
    return book_.finish(d, best_id, best, gate_, gated_, ukf_, cfg_);
  }

 protected:
  void addPoseNoise(const Mat3& Q) override { book_.addPoseNoise(ukf_, Q); }

 private:
  /// Association candidates: markers the ruler can physically reach from the predicted pose.
  /// The window grows by the 3-sigma uncertainty of where the ruler is (position, and heading
  /// times L1), so that after a lock-out inflation the right marker is a candidate again; while
  /// tracking (cm-level sigma) the margin is negligible.
  bool reachable(const Pose& pose, const Marker& m, double margin) const {
    const double dx = m.x - pose.x(), dy = m.y - pose.y();
    // cheap pre-test, no trigonometry: the window's far corner (f + margin, l + margin) is at
    // most reach_radius_ + sqrt(2) margin from M
    const double r = reach_radius_ + M_SQRT2 * margin;
    if (dx * dx + dy * dy > r * r) return false;
    const Vec2 body = markerInBody(pose, m.x, m.y);
    return std::abs(body.x() - cfg_.ruler_offset) <= cfg_.reach_forward + margin &&
           std::abs(body.y()) <= cfg_.ruler_half_width + cfg_.reach_lateral + margin;
  }
  double reachMargin() const {
    const auto& P = ukf_.P();
    const double var = P(0, 0) + P(1, 1) + cfg_.ruler_offset * cfg_.ruler_offset * P(2, 2);
    return 3.0 * std::sqrt(std::max(var, 0.0));
  }
  /// Lock-out: every lockout_rejections consecutive rejections (gate or no candidate) the
  /// status is Lockout and the covariance is inflated, so the estimate re-acquires the markers
  /// in a bounded number of rejections instead of drifting away from them for ever.
  std::string name_;
  FilterConfig cfg_;
  SharedMapIndex map_;
  std::vector<uint32_t> near_;  ///< association candidates (reused)
  bool gated_;
  double gate_;
  U ukf_;
  Mat2 R_;
  double reach_radius_ = 0.0;  ///< radius around M enclosing the reachable window (no margin)
  std::vector<std::string> names_;
  int64_t utime_ = 0;
  detail::GateBook book_;  ///< gate decisions and lock-out
  PendingOdometry pending_;
  TanCache tan_;  ///< eq. 2's tangent, for predict() and the batch
};

}  // namespace

std::unique_ptr<Filter> detail::makeRulerFilter(const FilterConfig& cfg, const SharedMapIndex& map) {
  if (cfg.type == "dead_reckoning") return std::make_unique<DeadReckoningFilter>(cfg);
  if (cfg.type == "ukf") return std::make_unique<RulerUkf<3>>(cfg.type, cfg, map, false);
  if (cfg.type == "ukf_gated") return std::make_unique<RulerUkf<3>>(cfg.type, cfg, map, true);
  if (cfg.type == "ukf_calib") return std::make_unique<RulerUkf<5>>(cfg.type, cfg, map, true);
  return nullptr;
}

}  // namespace lcmloc::core
