// "ukf_landmarks": a 3-state (x, y, theta) UKF for data brought by users: odometry increments
// (delta_s, delta_theta; a robot may turn in place), range-bearing observations of map
// landmarks with a known id (association given) or an unknown one (nearest neighbour in
// Mahalanobis distance among the map, then the chi-square gate), and range-only beacon ranges
// (1-D update, gated). See docs/import_formats.md. With FilterConfig::calibration switched on,
// the state is augmented with self-calibration states (landmark_calibration.hpp): the odometry
// step is corrected by its scale and bias states, a beacon's range by its bias state.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "filter_internal.hpp"
#include "landmark_calibration.hpp"
#include "landmark_evidence.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/ruler_model.hpp"
#include "lcmloc/core/vehicle_model.hpp"

namespace lcmloc::core {
namespace {

using detail::decision;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr AngleMask kThetaMask = 1u << 2;
constexpr AngleMask kBearingMask = 1u << 1;

/// N: 3 (no calibration) or 3 + the calibration states of layout.
/// The association of a measurement without identity over the candidates tried: the one with
/// the smallest Mahalanobis distance, and how many passed the gate. It must be unique: when two
/// pass (the estimate too uncertain to tell them apart, after a lock-out say) the nearest one is
/// a guess, and a wrong guess pulls the estimate towards the wrong landmark or beacon, where the
/// next guesses agree with it. Refused as "ambiguous" (not a gate rejection: no lock-out counts it).
template <class Innov>
struct UniqueMatch {
  Innov best;
  int best_id = -1, inside = 0;
  void offer(int id, const Innov& c, double gate) {
    inside += c.mahalanobis <= gate;
    if (best_id < 0 || c.mahalanobis < best.mahalanobis) {
      best = c;
      best_id = id;
    }
  }
  /// Two or more passed the gate: d says so; true.
  bool ambiguous(GateDecision& d) const {
    if (inside < 2) return false;
    d.reason = "ambiguous";
    d.marker_id = best_id;
    d.mahalanobis = best.mahalanobis;
    return true;
  }
};

template <int N>
class LandmarkUkf final : public Filter {
  using U = Ukf<N>;

 public:
  LandmarkUkf(const FilterConfig& c, SharedMapIndex map, detail::CalibrationLayout layout)
      : cfg_(c), map_(std::move(map)), gated_(c.gate.enabled), gate2_(gated_ ? c.gate.threshold(2) : kInf),
        gate1_(gated_ ? c.gate.threshold(1) : kInf), ukf_(c.sigma, kThetaMask), cal_(std::move(layout)),
        names_(cal_.names) {
    book_.caps = detail::lockoutCaps(cfg_, names_);
    book_.inflate = false;  // a lock-out is a status; the way back is evidence_ (re-localization)
    reset();
  }

  const std::string& name() const override {
    static const std::string n = "ukf_landmarks";
    return n;
  }
  void stateInto(FilterState& s) const override {
    s.utime = utime_;
    s.x = ukf_.x();
    s.P = ukf_.P();
    detail::setNames(s, names_);
    s.status = book_.status;
  }
  void initialize(const FilterState& from) override {
    Eigen::VectorXd x = initialX();
    Eigen::MatrixXd P = initialP();
    detail::copyMatching(from, names_, x, P);
    ukf_.reset(x, P);
    utime_ = from.utime;
    last_odometry_.reset();
    book_.reset();
  }
  bool uses(Measurement m) const override {
    return m == Measurement::Landmark || m == Measurement::Beacon;
  }

  void predict(const OdometryInput& odo) override {
    const double dth = headingIncrement(odo, cfg_.wheelbase);
    if (!std::isfinite(odo.delta_s) || !std::isfinite(dth)) return;
    const double ds = odo.delta_s;
    if constexpr (N == 3) {
      const SinCosNear mid(ukf_.x()(2) + 0.5 * dth);  // the sigma points' midpoint headings lie around it
      auto f = [ds, dth, &mid](const typename U::Vector& s) -> typename U::Vector {
        return propagatePose(s, ds, dth, mid);
      };
      typename U::Matrix Q = U::Matrix::Zero();
      Q.diagonal() = detail::poseProcessNoise(cfg_, ds, dth);
      if (ukf_.predict(f, Q)) utime_ = odo.utime;
      evidence_.move(ds, dth);
    } else {
      // The step's time for the yaw-rate bias: since the previous increment (none: 0).
      const double dt = last_odometry_ && odo.utime > *last_odometry_ ? 1e-6 * double(odo.utime - *last_odometry_) : 0.0;
      last_odometry_ = odo.utime;
      double ds_m, dth_m;  // the step corrected by the mean calibration
      cal_.correct(ukf_.x(), ds, dth, dt, ds_m, dth_m);
      const SinCosNear mid(ukf_.x()(2) + 0.5 * dth_m);
      const detail::CalibrationLayout& cal = cal_;
      auto f = [ds, dth, dt, &mid, &cal](const typename U::Vector& s) -> typename U::Vector {
        double ds_c, dth_c;
        cal.correct(s, ds, dth, dt, ds_c, dth_c);
        typename U::Vector o = s;
        o.template head<3>() = propagatePose(Pose(s.template head<3>()), ds_c, dth_c, mid);
        return o;
      };
      Eigen::VectorXd q = Eigen::VectorXd::Zero(N);
      q.head<3>() = detail::poseProcessNoise(cfg_, ds_m, dth_m);
      cal_.addProcessNoise(cfg_.calibration, ds, dth, dt, q);
      typename U::Matrix Q = typename U::Vector(q).asDiagonal();
      if (ukf_.predict(f, Q)) utime_ = odo.utime;
      evidence_.move(ds_m, dth_m);
    }
  }

  std::optional<Relocalization> takeRelocalization() override { return std::exchange(relocalized_, std::nullopt); }

  /// The ruler is not this filter's sensor (uses() says so; the engine never calls this).

  std::optional<GateDecision> update(const LandmarkObservation& obs) override {
    GateDecision d = decision(obs.utime, obs.sensor, obs.seq, gate2_);
    typename U::Sigmas X;
    if (!std::isfinite(obs.range) || !(obs.range >= 0) || !std::isfinite(obs.bearing) ||
        !ukf_.sigmaPoints(X)) {
      d.reason = "bad_input";
      return d;
    }
    const double rs = obs.range_std > 0 ? obs.range_std : cfg_.landmarks.range_std;
    const double bs = obs.bearing_std > 0 ? obs.bearing_std : cfg_.landmarks.bearing_std;
    const Mat2 R = Vec2(rs * rs, bs * bs).asDiagonal();
    const double kappa = cfg_.landmarks.correlation_factor;
    const Mat2 R_update = kappa * R;
    const Vec2 z(obs.range, wrapAngle(obs.bearing));
    // The gate's distance against the observation's own variance (S less the update's share of
    // the correlation factor): the factor discounts how much an observation tells, not how far
    // from the prediction it may lie.
    auto gate_on_own = [&R, kappa](Innovation<N, 2>& in) {
      if (kappa == 1.0) return true;
      Mat2 S_inv;
      if (!inverseSpd<2>(Mat2(in.S - (kappa - 1.0) * R), S_inv)) return false;
      in.mahalanobis = in.v.dot(S_inv * in.v);
      return std::isfinite(in.mahalanobis);
    };
    Innovation<N, 2> best, cand;
    int best_id = -1;
    auto h_of = [](const Marker& m) {
      return [&m](const typename U::Vector& s) { return predictRangeBearing(Pose(s.template head<3>()), m.x, m.y); };
    };
    if (obs.landmark_id >= 0) {
      const Marker* known = knownOr(obs.landmark_id, d);
      if (!known) return d;
      const Marker& m = *known;
      if (ukf_.template innovate<2>(X, h_of(m), R_update, z, kBearingMask, best) && gate_on_own(best)) best_id = m.id;
      finish(d, best_id, best, gate2_);
      if (d.accepted) evidence_.clear();
      else if (d.reason == "gate") relocalize(d, obs, m, rs, bs);
      return d;
    } else {
      // Nearest neighbour: only landmarks whose distance from the predicted position can match
      // the measured range within 4 sigma (position and range) are tried: the index hands those
      // within range + slack of it, in map order.
      const auto& P = ukf_.P();
      const double slack = 4.0 * std::sqrt(std::max(P(0, 0) + P(1, 1), 0.0) + rs * rs);
      const Vec3 pose = ukf_.x().template head<3>();
      UniqueMatch<Innovation<N, 2>> match;
      map_->near(pose.x(), pose.y(), MapIndex::widen(obs.range + slack, pose.x(), pose.y()), near_);
      for (const uint32_t i : near_) {
        const Marker& m = (*map_)[i];
        const double dist = std::hypot(m.x - pose.x(), m.y - pose.y());
        if (std::abs(dist - obs.range) > slack) continue;
        if (ukf_.template innovate<2>(X, h_of(m), R_update, z, kBearingMask, cand) && gate_on_own(cand))
          match.offer(m.id, cand, gate2_);
      }
      if (match.ambiguous(d)) return d;
      return finish(d, match.best_id, match.best, gate2_);
    }
  }

  /// The map entry of a measurement's identity; nullptr, with d's reason "unknown_id", when the
  /// map has none.
  const Marker* knownOr(int id, GateDecision& d) const {
    const Marker* m = map_->find(id);
    if (!m) {
      d.reason = "unknown_id";
      d.marker_id = id;
    }
    return m;
  }

  std::optional<GateDecision> update(const BeaconRange& b) override {
    GateDecision d = decision(b.utime, b.sensor, b.seq, gate1_);
    typename U::Sigmas X;
    if (!std::isfinite(b.range) || !(b.range >= 0) || !ukf_.sigmaPoints(X)) {
      d.reason = "bad_input";
      return d;
    }
    const double rs = b.range_std > 0 ? b.range_std : cfg_.landmarks.beacon_std;
    Eigen::Matrix<double, 1, 1> R, z;
    R(0, 0) = rs * rs;
    z(0, 0) = b.range;
    auto h_of = [this](const Marker& m) {
      const int bias = cal_.biasIndex(m.id);  // its range-bias state (-1: none)
      return [&m, bias](const typename U::Vector& s) {
        Eigen::Matrix<double, 1, 1> r;
        r(0, 0) = std::hypot(m.x - s.x(), m.y - s.y());
        if (bias >= 0) r(0, 0) += s[bias];
        return r;
      };
    };
    Innovation<N, 1> best, cand;
    int best_id = -1;
    if (b.beacon_id >= 0) {
      const Marker* known = knownOr(b.beacon_id, d);
      if (!known) return d;
      if (ukf_.template innovate<1>(X, h_of(*known), R, z, 0u, best)) best_id = known->id;
      return finish(d, best_id, best, gate1_);
    }
    // Without an identity: the map entries whose distance from the predicted position can match
    // the range within 4 sigma (position and range) are tried, and the range is taken only when
    // exactly one of them passes the gate (a range is a circle: with the estimate uncertain, two
    // beacons at about the same distance cannot be told apart; "ambiguous", as for landmarks).
    const auto& P = ukf_.P();
    const auto& x = ukf_.x();
    const double var = std::max(P(0, 0) + P(1, 1), 0.0) + rs * rs;
    // The range-bias states (the last ones, when on): the widest a bias can make a range.
    double bias_extent = 0;
    for (int k = std::max(cal_.bias0, 0); cal_.bias0 >= 0 && k < cal_.size(); ++k)
      bias_extent = std::max(bias_extent, std::abs(x[k]) + 4.0 * std::sqrt(std::max(P(k, k), 0.0)));
    const double px = x(0), py = x(1);
    UniqueMatch<Innovation<N, 1>> match;
    map_->near(px, py, MapIndex::widen(b.range + 4.0 * std::sqrt(var) + bias_extent, px, py), near_);
    for (const uint32_t i : near_) {
      const Marker& m = (*map_)[i];
      const int bias = cal_.biasIndex(m.id);
      const double predicted = std::hypot(m.x - px, m.y - py) + (bias >= 0 ? x[bias] : 0.0);
      const double slack = 4.0 * std::sqrt(var + (bias >= 0 ? std::max(P(bias, bias), 0.0) : 0.0));
      if (std::abs(predicted - b.range) > slack) continue;
      if (ukf_.template innovate<1>(X, h_of(m), R, z, 0u, cand)) match.offer(m.id, cand, gate1_);
    }
    if (match.ambiguous(d)) return d;
    return finish(d, match.best_id, match.best, gate1_);
  }

 protected:
  void addPoseNoise(const Mat3& Q) override { book_.addPoseNoise(ukf_, Q); }

 private:
  void reset() {
    ukf_.reset(initialX(), initialP());
    evidence_.clear();
  }
  /// The initial state: the configuration's pose, the calibration states' prior means.
  typename U::Vector initialX() const {
    typename U::Vector x = U::Vector::Zero();
    x.template head<3>() = cfg_.initial_pose;
    for (int i = 3; i < N; ++i) x[i] = cal_.x0[i - 3];
    return x;
  }
  /// The initial covariance: p0_diag, then the calibration states' prior variances.
  typename U::Matrix initialP() const {
    typename U::Matrix P = U::Matrix::Zero();
    P.template topLeftCorner<3, 3>() = Mat3(cfg_.p0_diag.asDiagonal());
    for (int i = 3; i < N; ++i) P(i, i) = cal_.p0[i - 3];
    return P;
  }
  /// A refused observation of a known landmark is evidence: when enough of them agree on a pose
  /// (LandmarkEvidence), the filter starts again from it, and d says so.
  void relocalize(GateDecision& d, const LandmarkObservation& obs, const Marker& m, double rs, double bs) {
    const auto f = evidence_.add(obs.utime, m.id, m.x, m.y, obs.range, wrapAngle(obs.bearing), rs, bs,
                                 std::isfinite(gate2_) ? gate2_ : 9.21);
    if (!f) return;
    const Vec3 before = ukf_.x().template head<3>();
    // The pose from the evidence; the calibration states keep their estimate and variance (their
    // correlation with the old pose is dropped with it).
    typename U::Vector x = ukf_.x();
    typename U::Matrix P = ukf_.P();
    x.template head<3>() = f->pose;
    P.template topRows<3>().setZero();
    P.template leftCols<3>().setZero();
    P.template topLeftCorner<3, 3>() = f->P;
    ukf_.reset(x, P);
    book_.reset();
    Relocalization r;
    r.utime = obs.utime;
    r.fixes = f->observations;
    r.first_utime = f->first_utime;
    r.spread = f->spread;
    r.jump = std::hypot(f->pose.x() - before.x(), f->pose.y() - before.y());
    r.heading_change = wrapAngle(f->pose.z() - before.z());
    r.heading_std = std::sqrt(f->P(2, 2));
    r.from_landmarks = true;
    r.landmarks = f->landmarks;
    relocalized_ = r;
    d.accepted = true;
    d.reason = "relocalized";
  }
  template <int M>
  GateDecision finish(GateDecision& d, int id, Innovation<N, M>& in, double gate) {
    utime_ = std::max(utime_, d.utime);
    return book_.finish(d, id, in, gate, gated_, ukf_, cfg_);
  }

  FilterConfig cfg_;
  SharedMapIndex map_;
  std::vector<uint32_t> near_;  ///< nearest-neighbour candidates (reused)
  bool gated_;
  double gate2_, gate1_;
  U ukf_;
  detail::CalibrationLayout cal_;
  std::vector<std::string> names_;
  int64_t utime_ = 0;
  std::optional<int64_t> last_odometry_;  ///< the previous increment's time (the yaw-rate bias's dt)
  detail::GateBook book_;  ///< gate decisions and lock-out
  detail::LandmarkEvidence evidence_;  ///< refused observations of known landmarks, for re-localization
  std::optional<Relocalization> relocalized_;
};

/// The filter with N states when the layout has N (3 + up to 3 + kMaxBeaconBiasStates).
template <int N>
std::unique_ptr<Filter> makeSized(const FilterConfig& cfg, const SharedMapIndex& map, detail::CalibrationLayout l) {
  if constexpr (N > 6 + detail::kMaxBeaconBiasStates) {
    return nullptr;
  } else {
    if (l.size() == N) return std::make_unique<LandmarkUkf<N>>(cfg, map, std::move(l));
    return makeSized<N + 1>(cfg, map, std::move(l));
  }
}

}  // namespace

std::unique_ptr<Filter> detail::makeLandmarkFilter(const FilterConfig& cfg, const SharedMapIndex& map) {
  if (cfg.type != "ukf_landmarks") return nullptr;
  return makeSized<3>(cfg, map, CalibrationLayout::of(cfg, map->markers()));
}

}  // namespace lcmloc::core
