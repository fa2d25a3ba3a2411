#include "lcmloc/gps_experiment/experiment.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/scoring.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/report.hpp"

namespace lcmloc::gps_experiment {
namespace {

const sim::TruthState* truthAt(const std::vector<sim::TruthState>& truth, int64_t utime) {
  // truth is sampled on a fixed grid starting at truth.front().utime
  if (truth.size() < 2) return nullptr;
  const int64_t dt = truth[1].utime - truth[0].utime;
  const int64_t k = (utime - truth.front().utime) / dt;
  if (k < 0 || k >= static_cast<int64_t>(truth.size()) || truth[k].utime != utime) return nullptr;
  return &truth[k];
}

}  // namespace

int64_t settledFrom(const std::vector<scenario::TrackPoint>& track, const Options& opt) {
  int64_t start = -1;
  for (const auto& p : track) {
    const double e = std::hypot(p.estimate.x[0] - p.truth.x(), p.estimate.x[1] - p.truth.y());
    if (e >= opt.converged_m) {
      start = -1;
      continue;
    }
    if (start < 0) start = p.utime;
    if (static_cast<double>(p.utime - start) * 1e-6 >= opt.hold_s) break;
  }
  return start;
}

Result run(const sim::ScenarioConfig& sc, const std::vector<core::FilterConfig>& filters,
           const Options& opt) {
  Result r;
  r.scenario = scenario::runScenario(sc, filters);
  const auto& truth = r.scenario.truth;
  const int64_t t0 = truth.front().utime;
  // Error of a fix against the truth at its time (nullopt: no fix, or no truth sample then).
  auto fixError = [&](const sim::GpsFixSample& g) -> std::optional<double> {
    const auto* t = g.has_fix ? truthAt(truth, g.utime) : nullptr;
    if (!t) return std::nullopt;
    return std::hypot(g.x - t->x, g.y - t->y);
  };
  std::vector<double> gps_all;
  for (const auto& g : r.scenario.gps)
    if (const auto e = fixError(g)) gps_all.push_back(*e);
  r.gps_rmse_all_m = core::rms(gps_all);
  for (const auto& f : r.scenario.filters) {
    FilterSummary s;
    s.filter = f.filter;
    s.lockouts = f.lockout_events;
    for (const auto& d : f.decisions)
      if (d.sensor == "GPS") (d.accepted ? s.gps_accepted : s.gps_rejected)++;
    const auto& tr = f.track;
    const int64_t start = settledFrom(tr, opt);
    if (start >= 0) s.convergence_s = static_cast<double>(start - t0) * 1e-6;
    if (start >= 0) {
      std::vector<double> steady, gps;
      for (const auto& p : tr)
        if (p.utime >= start) steady.push_back(std::hypot(p.estimate.x[0] - p.truth.x(), p.estimate.x[1] - p.truth.y()));
      const auto st = core::errorStats(steady);
      s.steady_rmse_m = st.rmse;
      s.steady_max_m = st.max;
      for (const auto& g : r.scenario.gps)
        if (const auto e = g.utime >= start ? fixError(g) : std::nullopt) gps.push_back(*e);
      s.gps_rmse_m = core::rms(gps);
    }
    r.filters.push_back(s);
  }
  return r;
}

bool writeReport(const Result& r, const Options& opt, const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const int64_t t0 = r.scenario.truth.front().utime;
  nlohmann::json j;
  j["converged_m"] = opt.converged_m;
  j["hold_s"] = opt.hold_s;
  j["gps_rmse_all_m"] = r.gps_rmse_all_m;
  j["truth_start"] = {r.scenario.truth.front().x, r.scenario.truth.front().y};
  for (const auto& s : r.filters) {
    // A filter that never converged has no steady state: null, not a zero error.
    auto steady = [&s](double v) { return s.converged() ? nlohmann::json(v) : nlohmann::json(nullptr); };
    j["filters"][s.filter] = {{"converged", s.converged()},
                              {"convergence_s", steady(s.convergence_s)}, {"steady_rmse_m", steady(s.steady_rmse_m)},
                              {"steady_max_m", steady(s.steady_max_m)}, {"gps_rmse_same_period_m", steady(s.gps_rmse_m)},
                              {"ratio_to_gps", steady(s.gps_rmse_m > 0 ? s.steady_rmse_m / s.gps_rmse_m : 0.0)},
                              {"gps_accepted", s.gps_accepted}, {"gps_rejected", s.gps_rejected},
                              {"lockouts", s.lockouts}};
  }
  eval::writeJson(j, dir + "/report.json");
  {
    std::ofstream f(dir + "/truth.dat");
    f << "# t[s] x y\n";
    for (const auto& t : r.scenario.truth) f << (t.utime - t0) * 1e-6 << ' ' << t.x << ' ' << t.y << '\n';
    std::ofstream g(dir + "/gps.dat");
    g << "# t[s] x y err\n";
    for (const auto& fx : r.scenario.gps) {
      if (!fx.has_fix) continue;
      const auto& tr = r.scenario.truth;
      const int64_t k = (fx.utime - t0) / (tr[1].utime - tr[0].utime);
      const double e = k >= 0 && k < static_cast<int64_t>(tr.size())
                           ? std::hypot(fx.x - tr[k].x, fx.y - tr[k].y) : 0.0;
      g << (fx.utime - t0) * 1e-6 << ' ' << fx.x << ' ' << fx.y << ' ' << e << '\n';
    }
  }
  std::string plot_a, plot_b;
  for (const auto& f : r.scenario.filters) {
    std::ofstream d(dir + "/" + f.filter + ".dat");
    d << "# t[s] x y err heading_err[rad]";
    for (const auto& c : f.track.empty() ? std::vector<core::CalibrationValue>{} : core::calibrationValues(f.track.front().estimate))
      d << ' ' << c.name << ' ' << c.name << "_sigma";
    d << '\n';
    for (const auto& p : f.track) {
      d << (p.utime - t0) * 1e-6 << ' ' << p.estimate.x[0] << ' ' << p.estimate.x[1] << ' '
        << std::hypot(p.estimate.x[0] - p.truth.x(), p.estimate.x[1] - p.truth.y()) << ' '
        << core::wrapAngle(p.estimate.x[2] - p.truth.z());
      for (const auto& c : core::calibrationValues(p.estimate)) d << ' ' << c.value << ' ' << c.sigma;
      d << '\n';
    }
    plot_a += ", '" + f.filter + ".dat' using 2:3 with lines lw 2 title '" + f.filter + "'";
    plot_b += ", '" + f.filter + ".dat' using 1:4 with lines lw 2 title '" + f.filter + "'";
  }
  std::ofstream gp(dir + "/plot.gp");
  gp << "set terminal pngcairo size 900,700 noenhanced\nset grid\n"
     << "set output 'fig1a_tracks.png'\nset title 'Fig. 1a: true, GPS and fused tracks'\n"
     << "set xlabel 'x [m]'\nset ylabel 'y [m]'\nset size ratio -1\nset key top left\n"
     << "plot 'truth.dat' using 2:3 with lines lw 3 lc rgb 'black' title 'true', "
     << "'gps.dat' using 2:3 with points pt 7 ps 0.5 lc rgb '#999999' title 'GPS'" << plot_a << "\n"
     << "set output 'fig1b_error.png'\nset size noratio\nset title 'Fig. 1b: position error'\n"
     << "set xlabel 't [s]'\nset ylabel 'error [m]'\nset logscale y\nset key top right\n"
     << "plot 'gps.dat' using 1:4 with points pt 7 ps 0.5 lc rgb '#999999' title 'GPS'" << plot_b << "\n";
  gp.close();
  return eval::runGnuplot(dir, "plot.gp") == 0;
}

}  // namespace lcmloc::gps_experiment
