// Metrics of recorded estimates against truth (definitions: docs/evaluate.md).
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <boost/math/distributions/chi_squared.hpp>

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

double chi2QuantileAnyDof(double p, double dof) {
  if (!(dof > 0)) throw std::invalid_argument("chi2: dof must be positive");
  if (!(p > 0 && p < 1)) throw std::invalid_argument("chi2: probability must be in (0, 1)");
  return boost::math::quantile(boost::math::chi_squared_distribution<double>(dof), p);
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

ErrorStats errorStats(const std::vector<double>& values) {
  ErrorStats s;
  std::vector<double> a;
  a.reserve(values.size());
  double sum = 0, sum_sq = 0;
  for (double v : values) {
    a.push_back(std::abs(v));
    sum += a.back();
    sum_sq += v * v;
    s.max = std::max(s.max, a.back());
  }
  s.n = static_cast<int64_t>(a.size());
  if (a.empty()) return s;
  const auto n = static_cast<double>(a.size());
  s.rmse = std::sqrt(sum_sq / n);
  s.mean = sum / n;
  s.median = percentile(a, 0.5);
  s.p95 = percentile(a, 0.95);
  return s;
}

ConsistencyStats consistency(const std::vector<double>& values, const std::vector<int>& dofs, double confidence) {
  ConsistencyStats c;
  if (values.empty() || values.size() != dofs.size()) return c;
  const double tail = (1.0 - confidence) / 2.0;
  c.dof = dofs.front();
  c.samples = static_cast<int64_t>(values.size());
  double sum = 0, total_dof = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    sum += values[i];
    total_dof += dofs[i];
  }
  const auto n = static_cast<double>(values.size());
  c.mean = sum / n;
  // n * mean is chi-square with the summed dof when the samples are independent and consistent.
  c.mean_lo = chi2QuantileAnyDof(tail, total_dof) / n;
  c.mean_hi = chi2QuantileAnyDof(1.0 - tail, total_dof) / n;
  c.sample_lo = chi2QuantileAnyDof(tail, c.dof);
  c.sample_hi = chi2QuantileAnyDof(1.0 - tail, c.dof);
  int64_t inside = 0;
  for (double v : values) inside += (v >= c.sample_lo && v <= c.sample_hi) ? 1 : 0;
  c.fraction_inside = static_cast<double>(inside) / n;
  c.verdict = c.mean > c.mean_hi ? "optimistic" : c.mean < c.mean_lo ? "conservative" : "honest";
  c.effective_samples = effectiveSampleSize(values);
  const double dof_per_sample = total_dof / n;
  c.mean_lo_effective = chi2QuantileAnyDof(tail, c.effective_samples * dof_per_sample) / c.effective_samples;
  c.mean_hi_effective = chi2QuantileAnyDof(1.0 - tail, c.effective_samples * dof_per_sample) / c.effective_samples;
  c.verdict_effective = c.mean > c.mean_hi_effective   ? "optimistic"
                        : c.mean < c.mean_lo_effective ? "conservative"
                                                       : "honest";
  return c;
}

double effectiveSampleSize(const std::vector<double>& x) {
  const std::size_t n = x.size();
  if (n < 4) return static_cast<double>(n);
  double mean = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(n);
  auto autocov = [&](std::size_t lag) {
    double s = 0;
    for (std::size_t i = 0; i + lag < n; ++i) s += (x[i] - mean) * (x[i + lag] - mean);
    return s / static_cast<double>(n);
  };
  const double c0 = autocov(0);
  if (!(c0 > 0)) return static_cast<double>(n);
  // Geyer (1992): sum pairs rho(2m) + rho(2m+1) while they stay positive.
  double sum = 0;  // sum of rho(k), k >= 1
  constexpr std::size_t kMaxLag = 20000;  // bounds the cost (n * lags) of very long correlations
  for (std::size_t m = 0; 2 * m + 1 < n && 2 * m + 1 <= kMaxLag; ++m) {
    const double r0 = m == 0 ? 1.0 : autocov(2 * m) / c0;
    const double r1 = autocov(2 * m + 1) / c0;
    if (r0 + r1 <= 0) break;
    sum += (m == 0 ? 0.0 : r0) + r1;
  }
  const double tau = std::max(1.0, 1.0 + 2.0 * sum);
  return std::max(1.0, static_cast<double>(n) / tau);
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

DriftStats drift(const std::vector<ScoredPose>& pts, double length) {
  DriftStats d;
  d.length_m = length;
  std::vector<double> pct;
  std::size_t j = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < pts.size() && pts[j].distance - pts[i].distance < length) ++j;
    if (j >= pts.size()) break;
    const double travelled = pts[j].distance - pts[i].distance;
    pct.push_back(100.0 * std::hypot(pts[j].err_x - pts[i].err_x, pts[j].err_y - pts[i].err_y) / travelled);
  }
  d.segments = static_cast<int64_t>(pct.size());
  if (pct.empty()) return d;
  double sum = 0;
  for (double p : pct) {
    sum += p;
    d.max_pct = std::max(d.max_pct, p);
  }
  d.mean_pct = sum / static_cast<double>(pct.size());
  d.median_pct = percentile(pct, 0.5);
  return d;
}

}  // namespace

TrackScore scoreTrack(const EstimateTrack& track, const std::vector<TruthPose>& truth, const EvaluateOptions& opt) {
  TrackScore sc;
  sc.channel = track.channel;
  sc.filters = track.filters;
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
      Eigen::LLT<Eigen::Matrix2d> llt2(p2);
      if (llt2.info() == Eigen::Success) {
        const Eigen::Vector2d v(p.err_x, p.err_y);
        p.nees2 = v.dot(llt2.solve(v));
        p.cov_xy = p2;
        p.has_cov = true;
      }
      Eigen::LLT<Eigen::Matrix3d> llt3(e.cov);
      if (t->has_heading && llt3.info() == Eigen::Success) {
        const Eigen::Vector3d v(p.err_x, p.err_y, p.err_heading);
        p.nees3 = v.dot(llt3.solve(v));
      }
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
  for (double len : opt.segment_lengths) sc.drift.push_back(drift(sc.points, len));
  sc.nees3 = consistency(nees3, dof3, opt.confidence);
  sc.nees2 = consistency(nees2, dof2, opt.confidence);
  return sc;
}

GateStats gateStatistics(const std::vector<GateRecord>& gates, double confidence) {
  struct Acc {
    GateGroup g;
    std::vector<double> nis;
    std::vector<int> dofs;
    double nis_all = 0;
    int64_t n_all = 0;
  };
  std::map<std::pair<std::string, std::string>, Acc> fs, f, s;
  auto add = [](Acc& a, const GateRecord& r) {
    ++a.g.decisions;
    ++a.g.reasons[r.reason];
    if (r.reason == "dead_reckoning") { ++a.g.ignored; return; }
    (r.accepted ? a.g.accepted : a.g.rejected)++;
    if (!std::isfinite(r.nis)) return;
    a.nis_all += r.nis;
    ++a.n_all;
    if (r.accepted && r.dim > 0) {
      a.nis.push_back(r.nis);
      a.dofs.push_back(r.dim);
    }
  };
  for (const auto& r : gates) {
    add(fs[{r.filter, r.sensor}], r);
    add(f[{r.filter, "*"}], r);
    add(s[{"*", r.sensor}], r);
  }
  auto collect = [&](std::map<std::pair<std::string, std::string>, Acc>& m) {
    std::vector<GateGroup> out;
    for (auto& [key, a] : m) {
      a.g.filter = key.first;
      a.g.sensor = key.second;
      a.g.nis_mean_all = a.n_all ? a.nis_all / static_cast<double>(a.n_all) : 0.0;
      double dof_sum = 0;
      for (int d : a.dofs) dof_sum += d;
      a.g.mean_dof = a.dofs.empty() ? 0.0 : dof_sum / static_cast<double>(a.dofs.size());
      // Mixed dimensions: the per-sample interval of the most common one.
      if (!a.dofs.empty()) {
        std::map<int, int> count;
        for (int d : a.dofs) ++count[d];
        const int mode = std::max_element(count.begin(), count.end(),
                                          [](const auto& x, const auto& y) { return x.second < y.second; })->first;
        std::vector<int> dofs = a.dofs;
        std::vector<double> nis = a.nis;
        for (std::size_t i = 0; i < dofs.size(); ++i)
          if (dofs[i] == mode) { std::swap(dofs[0], dofs[i]); std::swap(nis[0], nis[i]); break; }
        a.g.nis = consistency(nis, dofs, confidence);
      }
      out.push_back(a.g);
    }
    return out;
  };
  GateStats st;
  st.by_filter_sensor = collect(fs);
  st.by_filter = collect(f);
  st.by_sensor = collect(s);
  return st;
}

}  // namespace lcmloc::eval
