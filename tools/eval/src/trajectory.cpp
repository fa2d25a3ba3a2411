// Metrics of recorded estimates against truth (definitions: docs/evaluate.md).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>


#include "lcmloc/core/angles.hpp"
#include "lcmloc/eval/trajectory.hpp"

namespace lcmloc::eval {

std::optional<TruthPose> interpolateTruth(const std::vector<TruthPose>& truth, int64_t utime,
                                          int64_t max_gap_us, TruthMiss* why) {
  auto miss = [&](TruthMiss m) -> std::optional<TruthPose> {
    if (why) *why = m;
    return std::nullopt;
  };
  if (why) *why = TruthMiss::kNone;
  if (truth.empty() || utime < truth.front().utime) return miss(TruthMiss::kBefore);
  if (utime > truth.back().utime) return miss(TruthMiss::kAfter);
  auto hi = std::lower_bound(truth.begin(), truth.end(), utime,
                             [](const TruthPose& s, int64_t t) { return s.utime < t; });
  if (hi->utime == utime) return *hi;
  const TruthPose& a = *(hi - 1);
  const TruthPose& b = *hi;
  const uint64_t span = utimeSpan(a.utime, b.utime);  // no overflow whatever the utimes
  if (max_gap_us > 0 && span > static_cast<uint64_t>(max_gap_us)) return miss(TruthMiss::kGap);
  const double w = static_cast<double>(utimeSpan(a.utime, utime)) / static_cast<double>(span);
  TruthPose s;
  s.utime = utime;
  s.x = a.x + w * (b.x - a.x);
  s.y = a.y + w * (b.y - a.y);
  s.has_heading = a.has_heading && b.has_heading;
  s.heading = s.has_heading ? core::wrapAngle(a.heading + w * core::wrapAngle(b.heading - a.heading)) : 0.0;
  return s;
}

namespace {

/// Cumulative path length of the truth at each sample.
std::vector<double> cumulativeDistance(const std::vector<TruthPose>& truth) {
  std::vector<double> s(truth.size(), 0.0);
  for (std::size_t i = 1; i < truth.size(); ++i)
    s[i] = s[i - 1] + std::hypot(truth[i].x - truth[i - 1].x, truth[i].y - truth[i - 1].y);
  return s;
}

/// Path length at utime (inside the truth span): the distance to the sample before plus the
/// straight piece to the interpolated position.
double distanceAt(const std::vector<TruthPose>& truth, const std::vector<double>& cum, const TruthPose& at) {
  auto hi = std::lower_bound(truth.begin(), truth.end(), at.utime,
                             [](const TruthPose& s, int64_t t) { return s.utime < t; });
  const auto k = static_cast<std::size_t>(hi - truth.begin());
  if (hi->utime == at.utime || k == 0) return cum[k];
  const TruthPose& a = truth[k - 1];
  return cum[k - 1] + std::hypot(at.x - a.x, at.y - a.y);
}

}  // namespace

TrackScore scoreTrack(const EstimateTrack& track, const std::vector<TruthPose>& truth, const EvaluateOptions& opt) {
  TrackScore sc;
  sc.channel = track.channel;
  sc.filters = track.filters;
  sc.calibration = track.calibration;
  sc.estimates = static_cast<int64_t>(track.poses.size());
  if (!track.poses.empty()) {
    sc.first_utime = track.poses.front().utime;
    sc.last_utime = track.poses.back().utime;
  }
  const auto cum = cumulativeDistance(truth);
  const auto max_gap_us = static_cast<int64_t>(std::llround(opt.max_truth_gap_s * 1e6));
  std::vector<double> pos_err, head_err, nees3, nees2;
  std::vector<int> dof3, dof2;
  sc.has_heading = !truth.empty();
  bool skipped = false;
  for (const auto& e : track.poses) {
    TruthMiss why = TruthMiss::kNone;
    const auto t = interpolateTruth(truth, e.utime, max_gap_us, &why);
    if (!t) {
      skipped = true;
      (why == TruthMiss::kBefore ? sc.before_truth : why == TruthMiss::kAfter ? sc.after_truth : sc.in_truth_gap)++;
      continue;
    }
    ScoredPose p;
    p.after_skip = skipped && !sc.points.empty();
    skipped = false;
    p.utime = e.utime;
    p.x = e.x;
    p.y = e.y;
    p.theta = e.theta;
    p.truth_x = t->x;
    p.truth_y = t->y;
    p.truth_heading = t->heading;
    p.err_x = e.x - t->x;
    p.err_y = e.y - t->y;
    p.err = std::hypot(p.err_x, p.err_y);
    p.err_heading = t->has_heading ? core::wrapAngle(e.theta - t->heading) : 0.0;
    if (!t->has_heading) sc.has_heading = false;
    p.distance = distanceAt(truth, cum, *t);
    if (e.has_cov) {
      const Eigen::Matrix2d p2 = e.cov.topLeftCorner<2, 2>();
      if (const auto n2 = core::nees<2>(Eigen::Vector2d(p.err_x, p.err_y), p2)) {
        p.nees2 = *n2;
        p.cov_xy = p2;
        p.has_cov = true;
      }
      if (t->has_heading)
        if (const auto n3 = core::nees<3>(Eigen::Vector3d(p.err_x, p.err_y, p.err_heading), e.cov)) p.nees3 = *n3;
    }
    if (!p.has_cov) ++sc.without_covariance;
    pos_err.push_back(p.err);
    head_err.push_back(p.err_heading);
    if (p.nees2 >= 0) { nees2.push_back(p.nees2); dof2.push_back(2); }
    if (p.nees3 >= 0) { nees3.push_back(p.nees3); dof3.push_back(3); }
    sc.points.push_back(p);
  }
  sc.scored = static_cast<int64_t>(sc.points.size());
  if (sc.points.empty()) {
    sc.has_heading = false;
    return sc;
  }
  sc.position = errorStats(pos_err);
  if (sc.has_heading) {
    sc.heading = errorStats(head_err);
  } else {
    nees3.clear();
    dof3.clear();
  }
  sc.path_length_m = sc.points.back().distance - sc.points.front().distance;
  sc.final_error_m = sc.points.back().err;
  sc.final_error_pct = sc.path_length_m > 0 ? 100.0 * sc.final_error_m / sc.path_length_m : 0.0;
  std::vector<core::DriftSample> along;
  along.reserve(sc.points.size());
  for (const auto& p : sc.points) along.push_back({p.distance, p.err_x, p.err_y});
  for (double len : opt.segment_lengths) sc.drift.push_back(core::drift(along, len));
  sc.nees3 = consistency(nees3, dof3, opt.confidence);
  sc.nees2 = consistency(nees2, dof2, opt.confidence);
  return sc;
}

std::vector<FaultGroup> faultStatistics(const std::vector<GateRecord>& gates,
                                        const std::vector<AnnouncedFault>& faults) {
  std::set<std::pair<std::string, int64_t>> keys;
  for (const auto& f : faults) keys.emplace(f.channel, f.measurement_seq);
  std::map<std::string, core::FaultCounts> by_filter;
  for (const auto& g : gates)
    core::countDecision(by_filter[g.filter], g.accepted, g.reason, keys.count({g.sensor, g.measurement_seq}) > 0);
  std::vector<FaultGroup> out;
  for (const auto& [filter, counts] : by_filter) out.push_back({filter, counts});
  return out;
}

std::vector<IdentityGroup> identityStatistics(const std::vector<GateRecord>& gates, const std::string& landmark_channel,
                                              const std::vector<std::pair<std::string, int64_t>>& unknown) {
  const std::set<std::pair<std::string, int64_t>> keys(unknown.begin(), unknown.end());
  std::map<std::string, IdentityGroup> by_filter;
  for (const auto& g : gates) {
    if (g.sensor != landmark_channel || core::isIgnoredDecision(g.reason)) continue;
    IdentityGroup& c = by_filter[g.filter];
    if (keys.count({g.sensor, g.measurement_seq})) {
      ++c.unknown_decided;
      c.unknown_accepted += g.accepted;
    } else {
      ++c.known_decided;
      c.known_accepted += g.accepted;
    }
  }
  std::vector<IdentityGroup> out;
  for (auto& [filter, c] : by_filter) {
    c.filter = filter;
    out.push_back(c);
  }
  return out;
}

ReplayComparison compareTracks(const EstimateTrack& recorded, const EstimateTrack& replayed) {
  ReplayComparison c;
  if (!recorded.filters.empty()) c.filter = recorded.filters.back();
  std::map<int64_t, const Estimate*> by_time, rec_by_time;
  for (const auto& e : replayed.poses) by_time[e.utime] = &e;
  for (const auto& e : recorded.poses) rec_by_time[e.utime] = &e;
  double worst = 0;
  for (const auto& [t, e] : rec_by_time) {
    const auto r = by_time.find(t);
    if (r == by_time.end()) continue;
    ++c.matched;
    worst = std::max(worst, std::hypot(e->x - r->second->x, e->y - r->second->y));
  }
  if (c.matched) c.max_diff_m = worst;
  return c;
}

}  // namespace lcmloc::eval
