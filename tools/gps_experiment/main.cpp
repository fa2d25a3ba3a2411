// lcmloc-gps-experiment: §3 of the time-varying EKF paper as a scenario (in process, no LCM):
// the paper's run (convergence, steady-state error against the raw GPS error, the figures of
// Fig. 1), then the same drive at its steady state over many seeds and GPS rates.
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/gps_experiment/monte_carlo.hpp"
#include "lcmloc/gps_experiment/printing.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-gps-experiment: GPS +-5 m, filter starts at (0, 0), truth at (150, 50) (seeds/002 §3); then "
               "--runs seeds on a drive of at least --min-drive s at each of --rates"};
  app::CommonOptions opts;
  opts.config = app::configDir() + "/gps_paper.yaml";
  app::addCommonOptions(app, opts);
  std::string out = "out/gps_experiment";
  std::vector<std::string> types{"tvekf", "ukf_gps", "dead_reckoning"};
  uint64_t seed = 0;
  gps_experiment::MonteCarloOptions mc;
  bool overwrite = false;
  app::addOutputOption(app, out, "output directory (report.json, montecarlo.json, figures)")->capture_default_str();
  app::addOverwriteFlag(app, overwrite);
  app.add_option("--filters", types, "filters to run")->delimiter(',')->capture_default_str();
  app.add_option("--seed", seed, "override scenario.seed")->check(app::seed());
  app.add_option("--converged", mc.score.converged_m, "convergence threshold [m]")->capture_default_str()->check(app::positive());
  app.add_option("--hold", mc.score.hold_s, "time the error must stay below it [s]")->capture_default_str()->check(app::nonNegative());
  app.add_option("--runs", mc.runs, "seeds of the steady-state runs (0: the paper's run only)")->capture_default_str()->check(CLI::Range(0, 100000));
  app.add_option("--rates", mc.rates_hz, "GPS rates of the steady-state runs [Hz]")->delimiter(',')->capture_default_str()->check(CLI::Range(0.01, 100.0));
  app.add_option("--min-drive", mc.min_drive_s, "the path repeats until the drive lasts this long [s]")->capture_default_str()->check(CLI::Range(0.0, 86400.0));

  return app::runProcess(app, argc, argv, opts, "lcmloc-gps-experiment", [&] {
    auto cfg = simconfig::loadSimSystemConfig(opts.config);
    app::prepareOutputDir(out, overwrite);
    if (seed) cfg.scenario.seed = seed;
    const auto filters = gps_experiment::filterConfigs(types, cfg.fusion.filter);
    spdlog::info("running '{}' (seed {}) with {} filter(s)", cfg.scenario.name, cfg.scenario.seed, filters.size());
    const auto r = gps_experiment::run(cfg.scenario, filters, mc.score);
    const bool plotted = gps_experiment::writeReport(r, mc.score, out);
    gps_experiment::printPaperRun(r, out, plotted);
    if (mc.runs == 0) return app::kExitOk;
    const auto m = gps_experiment::monteCarlo(cfg.scenario, filters, mc, [](int done, int total) {
      if (done == total || done % std::max(1, total / 10) == 0) spdlog::info("steady-state runs: {} of {}", done, total);
    });
    gps_experiment::writeMonteCarlo(m, mc, out);
    gps_experiment::printMonteCarlo(m, mc, out);
    return app::kExitOk;
  });
}
