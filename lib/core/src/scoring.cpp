// The one scoring library (definitions: docs/evaluate.md).
#include "lcmloc/core/scoring.hpp"

#include <algorithm>
#include <cmath>

#include "lcmloc/core/chi2.hpp"

namespace lcmloc::core {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double percentileNearestRank(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, k > 0 ? k - 1 : 0)];
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

double rms(const std::vector<double>& v) {
  if (v.empty()) return 0.0;
  double sum_sq = 0;
  for (double x : v) sum_sq += x * x;
  return std::sqrt(sum_sq / static_cast<double>(v.size()));
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

DriftStats drift(const std::vector<DriftSample>& pts, double length) {
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

bool isIgnoredDecision(const std::string& reason) { return reason == "dead_reckoning"; }

GateStats gateStatistics(const std::vector<GateRecord>& gates, double confidence) {
  struct Acc {
    GateGroup g;
    std::vector<double> nis;
    std::vector<int> dofs;
    double nis_all = 0;
    int64_t n_all = 0;
    int64_t run = 0, run_start = 0, run_last = 0;  ///< the current run of rejections
  };
  // A run of rejections ends at an acceptance (its length measured to it) or at the end.
  auto endRun = [](Acc& a, int64_t until) {
    if (a.run == 0) return;
    const double s = static_cast<double>(until - a.run_start) * 1e-6;
    if (a.run > a.g.longest_rejection_run || (a.run == a.g.longest_rejection_run && s > a.g.longest_rejection_s)) {
      a.g.longest_rejection_run = a.run;
      a.g.longest_rejection_s = s;
    }
    a.run = 0;
  };
  auto track = [&endRun](Acc& a, const GateRecord& r) {
    if (isIgnoredDecision(r.reason)) return;
    if (r.accepted) return endRun(a, r.utime);
    if (a.run++ == 0) a.run_start = r.utime;
    a.run_last = r.utime;
  };
  std::map<std::pair<std::string, std::string>, Acc> fs, f, s;
  auto add = [](Acc& a, const GateRecord& r) {
    ++a.g.decisions;
    ++a.g.reasons[r.reason];
    if (isIgnoredDecision(r.reason)) { ++a.g.ignored; return; }
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
    track(fs[{r.filter, r.sensor}], r);
    track(f[{r.filter, "*"}], r);
  }
  for (auto* m : {&fs, &f})
    for (auto& [key, a] : *m) endRun(a, a.run_last);
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

void countDecision(FaultCounts& c, bool accepted, const std::string& reason, bool is_fault) {
  if (is_fault) ++c.faults_decided;
  if (isIgnoredDecision(reason)) {
    ++c.ignored;
    return;
  }
  (accepted ? c.accepted : c.rejected)++;
  if (is_fault) (accepted ? c.faults_accepted : c.faults_rejected)++;
  else if (!accepted) ++c.valid_rejected;
}

}  // namespace lcmloc::core
