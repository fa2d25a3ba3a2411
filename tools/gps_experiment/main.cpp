// lcmloc-gps-experiment: §3 of the time-varying EKF paper as a scenario (in process, no LCM):
// convergence time and steady-state error of tvekf / ukf_gps / dead reckoning against the raw
// GPS error; report.json and the figures of Fig. 1.
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/gps_experiment/experiment.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-gps-experiment: GPS +-5 m, filter starts at (0, 0), truth at (150, 50) (seeds/002 §3)"};
  common::CommonOptions opts;
  opts.config = common::configDir() + "/gps_paper.yaml";
  common::addCommonOptions(app, opts);
  std::string out = "out/gps_experiment";
  std::vector<std::string> types{"tvekf", "ukf_gps", "dead_reckoning"};
  uint64_t seed = 0;
  gps_experiment::Options eo;
  bool overwrite = false;
  common::addOutputOption(app, out, "output directory (report.json, figures)")->capture_default_str();
  common::addOverwriteFlag(app, overwrite);
  app.add_option("--filters", types, "filters to run")->delimiter(',')->capture_default_str();
  app.add_option("--seed", seed, "override scenario.seed")
      ->check(lcmloc::common::seed());
  app.add_option("--converged", eo.converged_m, "convergence threshold [m]")->capture_default_str()->check(lcmloc::common::positive());
  app.add_option("--hold", eo.hold_s, "time the error must stay below it [s]")->capture_default_str()->check(lcmloc::common::nonNegative());

  return common::runProcess(app, argc, argv, opts, "lcmloc-gps-experiment", [&] {
    auto cfg = common::loadSimSystemConfig(opts.config);
    common::prepareOutputDir(out, overwrite);
    if (seed) cfg.scenario.seed = seed;
    std::vector<core::FilterConfig> filters;
    for (const auto& t : types) {
      YAML::Node n;
      n["type"] = t;
      filters.push_back(common::parseFilterConfig(n, cfg.fusion.filter, "--filters", "fusion.filter"));
    }
    spdlog::info("running '{}' (seed {}) with {} filter(s)", cfg.scenario.name, cfg.scenario.seed, filters.size());
    const auto r = gps_experiment::run(cfg.scenario, filters, eo);
    const bool plotted = gps_experiment::writeReport(r, eo, out);
    std::printf("%-16s %12s %14s %12s %14s %8s %8s\n", "filter", "converge[s]", "steady_rmse[m]", "max[m]",
                "gps_rmse[m]", "gps_rej", "lockout");
    for (const auto& s : r.filters) {
      if (s.converged())
        std::printf("%-16s %12.2f %14.3f %12.3f %14.3f %8d %8d\n", s.filter.c_str(), s.convergence_s,
                    s.steady_rmse_m, s.steady_max_m, s.gps_rmse_m, s.gps_rejected, s.lockouts);
      else  // no steady state to score
        std::printf("%-16s %12s %14s %12s %14s %8d %8d\n", s.filter.c_str(), "never", "-", "-", "-",
                    s.gps_rejected, s.lockouts);
    }
    std::printf("raw GPS RMSE over the run: %.3f m; report: %s/report.json%s\n", r.gps_rmse_all_m, out.c_str(),
                plotted ? ", figures fig1a_tracks.png, fig1b_error.png" : " (gnuplot failed: no figures)");
    return common::kExitOk;
  });
}
