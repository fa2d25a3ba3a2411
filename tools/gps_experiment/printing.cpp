#include "lcmloc/gps_experiment/printing.hpp"

#include <cstdio>

#include "lcmloc/app/config.hpp"

namespace lcmloc::gps_experiment {

std::vector<core::FilterConfig> filterConfigs(const std::vector<std::string>& types, const core::FilterConfig& base) {
  std::vector<core::FilterConfig> filters;
  for (const auto& t : types) {
    YAML::Node n;
    n["type"] = t;
    filters.push_back(app::parseFilterConfig(n, base, "--filters", "fusion.filter"));
  }
  return filters;
}

void printPaperRun(const Result& r, const std::string& dir, bool plotted) {
  std::printf("%-16s %12s %14s %12s %14s %8s %8s\n", "filter", "converge[s]", "steady_rmse[m]", "max[m]",
              "gps_rmse[m]", "gps_rej", "lockout");
  for (const auto& s : r.filters) {
    if (s.converged())
      std::printf("%-16s %12.2f %14.3f %12.3f %14.3f %8d %8d\n", s.filter.c_str(), s.convergence_s, s.steady_rmse_m,
                  s.steady_max_m, s.gps_rmse_m, s.gps_rejected, s.lockouts);
    else  // no steady state to score
      std::printf("%-16s %12s %14s %12s %14s %8d %8d\n", s.filter.c_str(), "never", "-", "-", "-", s.gps_rejected,
                  s.lockouts);
  }
  std::printf("raw GPS RMSE over the run: %.3f m; report: %s/report.json%s\n", r.gps_rmse_all_m, dir.c_str(),
              plotted ? ", figures fig1a_tracks.png, fig1b_error.png" : " (gnuplot failed: no figures)");
}

void printMonteCarlo(const McResult& m, const MonteCarloOptions& opt, const std::string& dir) {
  std::printf("\nsteady state: %d seeds, drive %.0f s (%.0f m); settled = error below %.1f m for %.1f s\n", opt.runs,
              m.drive_s, m.path_m, opt.score.converged_m, opt.score.hold_s);
  std::printf("%-8s %-16s %8s %12s %10s %12s %10s %8s %9s %12s\n", "gps[Hz]", "filter", "settled", "rmse_med[m]",
              "rmse_p95", "settle_med[s]", "settle_max", "NEES", "lockouts", "2nd_fix_max");
  for (const auto& g : m.groups) {
    if (g.converged == 0) {
      std::printf("%-8.2f %-16s %5d/%-3d %12s %10s %12s %10s %8s %9d %12.2f\n", g.rate_hz, g.filter.c_str(), g.converged,
                  static_cast<int>(g.runs.size()), "-", "-", "-", "-", "-", g.with_lockout, g.second_fix_error_max);
      continue;
    }
    std::printf("%-8.2f %-16s %5d/%-3d %12.3f %10.3f %12.2f %10.2f %8.2f %9d %12.2f\n", g.rate_hz, g.filter.c_str(),
                g.converged, static_cast<int>(g.runs.size()), g.rmse_median, g.rmse_p95, g.convergence_median,
                g.convergence_max, g.nees_mean, g.with_lockout, g.second_fix_error_max);
  }
  std::printf("2nd_fix_max: the largest position error just after the second GPS fix [m]\n");
  std::printf("report: %s/montecarlo.json\n", dir.c_str());
}

}  // namespace lcmloc::gps_experiment
