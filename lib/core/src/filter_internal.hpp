#pragma once
// Helpers shared by the filter implementations (not installed; src/ only).
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "lcmloc/core/filter.hpp"

namespace lcmloc::core::detail {

/// Hot swap: copies every state of `from` that has the same name as one of `names` (x, y,
/// theta always) into x, P (pre-filled with the filter's initial values), with the covariance
/// among copied states; cross-covariances to other states are zero. Throws
/// std::invalid_argument when `from` is malformed or not finite.
void copyMatching(const FilterState& from, const std::vector<std::string>& names,
                  Eigen::VectorXd& x, Eigen::MatrixXd& P);

/// The odometry-only and magnetic-ruler filters ("dead_reckoning", "ukf", "ukf_gated",
/// "ukf_calib") over the map; nullptr for another type. The configuration is checked already.
std::unique_ptr<Filter> makeRulerFilter(const FilterConfig& cfg, const SharedMapIndex& map);

/// The GNSS filters ("tvekf", "ukf_gps"); nullptr for another type. Throws
/// std::invalid_argument for an invalid configuration.
std::unique_ptr<Filter> makeGnssFilter(const FilterConfig& cfg);

/// The landmark/beacon filter ("ukf_landmarks") over the map; nullptr for another type.
std::unique_ptr<Filter> makeLandmarkFilter(const FilterConfig& cfg, const SharedMapIndex& map);

/// s.names = names, unless they are the same already (the engine fills one FilterState for
/// every state it publishes: the names seldom change).
inline void setNames(FilterState& s, const std::vector<std::string>& names) {
  if (s.names != names) s.names = names;
}

/// Pose process noise of one odometry step (x, y, theta variances): Pw over pw_distance of
/// travel plus pw_turn |dtheta| on the heading.
Vec3 poseProcessNoise(const FilterConfig& c, double ds, double dtheta);

/// Why this fix cannot be applied ("" when it can): unusableState of the pose with its
/// (symmetrized) covariance.
inline std::string fixProblem(const PoseFix& fix) {
  FilterState s;
  s.x = fix.pose;
  s.P = 0.5 * (fix.cov + fix.cov.transpose());
  return unusableState(s);
}
inline bool usableFix(const PoseFix& fix) { return fixProblem(fix).empty(); }

/// A gate decision for measurement `seq` of `sensor` at utime, with the gate's threshold;
/// not accepted, no reason yet (the filter fills in the rest).
inline GateDecision decision(int64_t utime, const std::string& sensor, int64_t seq, double gate) {
  GateDecision d;
  d.utime = utime;
  d.sensor = sensor;
  d.measurement_seq = seq;
  d.gate = gate;
  return d;
}

/// A state's variance and the 1-sigma beyond which lock-out inflation does not take it.
struct InflateCap {
  int index;
  double max_std;
};

/// Lock-out inflation: scales the variance of each listed state by f (its row and column by
/// sqrt(f): D P D stays positive definite and keeps the correlations), but not beyond its cap;
/// a variance already at or above cap^2 stays as it is.
template <typename M>
void inflateCapped(M& P, const std::vector<InflateCap>& states, double f) {
  for (const InflateCap& c : states) {
    const double g = std::min(f, c.max_std * c.max_std / P(c.index, c.index));
    if (!(g > 1.0)) continue;
    const double r = std::sqrt(g);
    P.row(c.index) *= r;
    P.col(c.index) *= r;
  }
}

/// The lock-out inflation caps of a filter with these state names: x, y at lockout_max_std, theta
/// at kLockoutMaxHeadingStd, odo_scale and steer_bias (ukf_calib) at their initial sigmas.
std::vector<InflateCap> lockoutCaps(const FilterConfig& cfg, const std::vector<std::string>& names);

/// Gate decision, correction and lock-out bookkeeping of the gated UKFs (the magnetic-ruler
/// filters and ukf_landmarks): FilterConfig::lockout_rejections consecutive rejections (gate or
/// no candidate) declare a lock-out and inflate the covariance by lockout_inflation (each state
/// up to its cap, see lockoutCaps), again after every further lockout_rejections, until a
/// measurement is accepted.
struct GateBook {
  std::vector<InflateCap> caps;  ///< lockoutCaps of the filter's states
  FilterStatus status = FilterStatus::Ok;
  int consecutive_rejections = 0;
  /// A lock-out inflates the covariance (the magnetic-ruler filters); false: the lock-out is a
  /// status only, the filter re-localizes from evidence ("ukf_landmarks").
  bool inflate = true;
  void reset() {
    status = FilterStatus::Ok;
    consecutive_rejections = 0;
  }
  /// Completes d for the best candidate id (< 0: none) with innovation in; corrects ukf when the
  /// innovation passes the gate (or the filter is ungated).
  template <class Ukf, class Innov>
  GateDecision& finish(GateDecision& d, int id, Innov& in, double gate, bool gated, Ukf& ukf,
                       const FilterConfig& cfg) {
    if (id < 0) {
      d.reason = "no_candidate";
      if (gated) reject(ukf, cfg);
      return d;
    }
    d.marker_id = id;
    d.innovation = in.v;
    d.mahalanobis = in.mahalanobis;
    if (gated && !(in.mahalanobis <= gate)) {
      d.reason = "gate";
      reject(ukf, cfg);
      return d;
    }
    ukf.correct(in);
    d.accepted = true;
    d.reason = gated ? "accepted" : "ungated";
    reset();
    return d;
  }
  /// An odometry gap (Filter::addPoseNoise): Q on the pose block; DeadReckoning until the next
  /// accepted measurement (a Lockout stays one).
  template <class Ukf>
  void addPoseNoise(Ukf& ukf, const Mat3& Q) {
    auto P = ukf.P();
    P.template topLeftCorner<3, 3>() += Q;
    ukf.reset(ukf.x(), P);
    if (status != FilterStatus::Lockout) status = FilterStatus::DeadReckoning;
  }
  template <class Ukf>
  void reject(Ukf& ukf, const FilterConfig& cfg) {
    ++consecutive_rejections;
    if (cfg.lockout_rejections > 0 && consecutive_rejections % cfg.lockout_rejections == 0) {
      status = FilterStatus::Lockout;
      if (!inflate) return;
      auto P = ukf.P();
      inflateCapped(P, caps, cfg.lockout_inflation);
      ukf.reset(ukf.x(), P);
    }
  }
};

/// The odometry/INS filters ("odo_ins", "odo_ins_uncal"); nullptr for another type. Throws
/// std::invalid_argument for an invalid configuration.
std::unique_ptr<Filter> makeOdoInsFilter(const FilterConfig& cfg);

}  // namespace lcmloc::core::detail
