#include "lcmloc/gps_experiment/monte_carlo.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <nlohmann/json.hpp>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/scoring.hpp"
#include "lcmloc/eval/report.hpp"

namespace lcmloc::gps_experiment {
namespace {

/// Time of the second GPS fix (-1: fewer fixes).
int64_t secondFixUtime(const std::vector<sim::GpsFixSample>& gps) {
  int n = 0;
  for (const auto& g : gps)
    if (g.has_fix && ++n == 2) return g.utime;
  return -1;
}

RunScore score(const scenario::ScenarioFilterResult& f, int64_t t0, int64_t second_fix, const Options& opt) {
  RunScore s;
  s.lockouts = f.lockout_events;
  if (!f.track.empty()) s.calibration = core::calibrationValues(f.track.back().estimate);
  for (const auto& p : f.track)  // the first pose at or after the second fix (the fix is applied then)
    if (second_fix >= 0 && p.utime >= second_fix) {
      s.second_fix_error_m = std::hypot(p.estimate.x[0] - p.truth.x(), p.estimate.x[1] - p.truth.y());
      break;
    }
  const int64_t start = settledFrom(f.track, opt);
  if (start < 0) return s;
  s.converged = true;
  s.convergence_s = static_cast<double>(start - t0) * 1e-6;
  std::vector<double> errors, nees;
  for (const auto& p : f.track) {
    if (p.utime < start) continue;
    const Eigen::Vector3d e(p.estimate.x[0] - p.truth.x(), p.estimate.x[1] - p.truth.y(),
                            core::wrapAngle(p.estimate.x[2] - p.truth.z()));
    errors.push_back(std::hypot(e.x(), e.y()));
    const Eigen::Matrix3d P = p.estimate.P.topLeftCorner<3, 3>();
    if (const auto n = core::nees<3>(e, P)) nees.push_back(*n);
  }
  const auto st = core::errorStats(errors);
  s.rmse_m = st.rmse;
  s.max_m = st.max;
  if (!nees.empty()) s.nees_mean = std::accumulate(nees.begin(), nees.end(), 0.0) / static_cast<double>(nees.size());
  return s;
}

void summarize(McGroup& g) {
  std::vector<double> rmse, conv, nees;
  for (const auto& r : g.runs) {
    g.with_lockout += r.lockouts > 0;
    g.second_fix_error_max = std::max(g.second_fix_error_max, r.second_fix_error_m);
    if (!r.converged) continue;
    ++g.converged;
    rmse.push_back(r.rmse_m);
    conv.push_back(r.convergence_s);
    nees.push_back(r.nees_mean);
  }
  g.rmse_median = core::percentile(rmse, 0.5);
  g.rmse_p95 = core::percentile(rmse, 0.95);
  g.convergence_median = core::percentile(conv, 0.5);
  g.convergence_p95 = core::percentile(conv, 0.95);
  g.convergence_max = core::percentile(conv, 1.0);
  if (!nees.empty()) g.nees_mean = std::accumulate(nees.begin(), nees.end(), 0.0) / static_cast<double>(nees.size());
}

}  // namespace

sim::PathConfig extendedPath(const sim::ScenarioConfig& sc, double min_drive_s) {
  sim::PathConfig p = sc.path;
  double lap = 0;
  for (const auto& s : sc.path.segments) lap += s.length;
  if (lap <= 0 || sc.vehicle.speed <= 0) return p;
  double length = lap;
  while (length / sc.vehicle.speed < min_drive_s) {
    p.segments.insert(p.segments.end(), sc.path.segments.begin(), sc.path.segments.end());
    length += lap;
  }
  return p;
}

McResult monteCarlo(const sim::ScenarioConfig& base, const std::vector<core::FilterConfig>& filters,
                    const MonteCarloOptions& opt, const std::function<void(int, int)>& progress) {
  McResult r;
  sim::ScenarioConfig sc = base;
  sc.path = extendedPath(base, opt.min_drive_s);
  for (const auto& s : sc.path.segments) r.path_m += s.length;
  for (double rate : opt.rates_hz)
    for (const auto& f : filters) r.groups.push_back(McGroup{rate, f.type, {}});
  const int total = opt.runs * static_cast<int>(opt.rates_hz.size());
  int done = 0;
  for (int i = 0; i < opt.runs; ++i) {
    for (std::size_t k = 0; k < opt.rates_hz.size(); ++k) {
      sc.seed = base.seed + static_cast<uint64_t>(i);
      sc.gps.rate_hz = opt.rates_hz[k];
      const scenario::ScenarioResult run = scenario::runScenario(sc, filters);
      const int64_t t0 = run.truth.front().utime;
      if (r.drive_s == 0) r.drive_s = static_cast<double>(run.truth.back().utime - t0) * 1e-6;
      for (std::size_t j = 0; j < run.filters.size(); ++j) {
        RunScore s = score(run.filters[j], t0, secondFixUtime(run.gps), opt.score);
        s.seed = sc.seed;
        r.groups[k * filters.size() + j].runs.push_back(s);
      }
      if (progress) progress(++done, total);
    }
  }
  for (auto& g : r.groups) summarize(g);
  return r;
}

void writeMonteCarlo(const McResult& r, const MonteCarloOptions& opt, const std::string& dir) {
  nlohmann::json j;
  j["runs"] = opt.runs;
  j["drive_s"] = r.drive_s;
  j["path_m"] = r.path_m;
  j["converged_m"] = opt.score.converged_m;
  j["hold_s"] = opt.score.hold_s;
  auto orNull = [](bool ok, double v) { return ok ? nlohmann::json(v) : nlohmann::json(nullptr); };
  for (const auto& g : r.groups) {
    nlohmann::json runs = nlohmann::json::array();
    for (const auto& s : g.runs) {
      runs.push_back({{"seed", s.seed}, {"converged", s.converged}, {"convergence_s", orNull(s.converged, s.convergence_s)},
                      {"rmse_m", orNull(s.converged, s.rmse_m)}, {"max_m", orNull(s.converged, s.max_m)},
                      {"nees_mean", orNull(s.converged, s.nees_mean)}, {"lockouts", s.lockouts},
                      {"second_fix_error_m", orNull(s.second_fix_error_m >= 0, s.second_fix_error_m)}});
      for (const auto& c : s.calibration)
        runs.back()["calibration"][c.name] = {{"value", c.value}, {"sigma", c.sigma}};
    }
    const bool any = g.converged > 0;
    j["groups"].push_back({{"gps_rate_hz", g.rate_hz}, {"filter", g.filter}, {"converged", g.converged},
                           {"with_lockout", g.with_lockout}, {"rmse_median_m", orNull(any, g.rmse_median)},
                           {"rmse_p95_m", orNull(any, g.rmse_p95)},
                           {"convergence_median_s", orNull(any, g.convergence_median)},
                           {"convergence_p95_s", orNull(any, g.convergence_p95)},
                           {"convergence_max_s", orNull(any, g.convergence_max)},
                           {"nees_mean", orNull(any, g.nees_mean)},
                           {"second_fix_error_max_m", orNull(g.second_fix_error_max >= 0, g.second_fix_error_max)},
                           {"runs", runs}});
  }
  eval::writeJson(j, dir + "/montecarlo.json");
}

}  // namespace lcmloc::gps_experiment
