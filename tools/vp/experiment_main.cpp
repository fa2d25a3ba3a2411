// lcmloc-vp-experiment: Victoria Park import + replay of tvekf / ukf_gps / dead_reckoning +
// score against held-out GPS fixes; report.json, drive.png, error.png.
#include <cstdio>

#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/vp/vp.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-vp-experiment: imports the Victoria Park files with every k-th GPS fix held out, replays the log "
      "through the fusion daemon's code once per filter and scores each fused track at the held-out fixes "
      "(RMSE, median, p95, max); writes report.json, drive.png and error.png."};
  app::CommonOptions opts;
  opts.config = app::configDir() + "/victoria_park.yaml";
  app::addCommonOptions(app, opts);
  vp::ImportOptions io;
  vp::ExperimentOptions eo;
  std::string dir = LCMLOC_VP_DIR;
  bool no_init = false, overwrite = false;
  app.add_option("--dir", dir, "data directory holding vp_odometry.csv and vp_gps.csv")->capture_default_str();
  app::addOutputOption(app, eo.out_dir, "output directory (report.json, figures)")->capture_default_str();
  app::addOverwriteFlag(app, overwrite);
  app.add_option("--filters", eo.filters, "filters to run")->delimiter(',')->capture_default_str();
  app.add_option("--holdout-every", io.holdout_every,
                 "hold every k-th fix out, k >= 2 (the filters get the others and are scored at these)")
      ->capture_default_str();
  app.add_option("--holdout-phase", io.holdout_phase, "fix i is held out when i % k == phase, phase in [0, k)")
      ->capture_default_str();
  app.add_option("--max-rows", io.max_rows,
                 "a slice: the first N odometry rows and the GPS rows of their time span (0 = all)")
      ->capture_default_str()->check(lcmloc::app::nonNegative());
  app.add_option("--gps-std", io.gps_std, "position_std written into the fixes [m] (0 = gnss.gps_std)")
      ->capture_default_str()
      ->check(lcmloc::app::nonNegative());
  app.add_flag("--no-gps-init", no_init, "start from fusion.filter.initial_pose instead of the first fixes");
  bool no_fit = false;
  app.add_flag("--no-fit", no_fit,
               "replay with the config's noise as given (default: each filter's noise fitted to the innovations of the "
               "fixes it is given, never the held-out ones)");

  return app::runProcess(app, argc, argv, opts, "lcmloc-vp-experiment", [&]() -> int {
    const auto cfg = app::loadSystemConfig(opts.config);
    vp::checkExperimentOptions(cfg, io, eo);  // before the output directory is made
    app::prepareOutputDir(eo.out_dir, overwrite);
    io.odometry_csv = dir + "/vp_odometry.csv";
    io.gps_csv = dir + "/vp_gps.csv";
    io.stop = [] { return app::stopRequested(); };
    eo.init_from_gps = !no_init;
    eo.fit_noise = !no_fit;
    const auto r = vp::runExperiment(cfg, io, eo);
    std::printf("%-16s %8s %8s %10s %10s %10s %10s %8s %10s %8s %8s\n", "filter", "poses", "scored", "rmse[m]",
                "median[m]", "p95[m]", "max[m]", "gps_rej", "rej_run[s]", "lockout", "reloc");
    for (const auto& s : r.scores)
      std::printf("%-16s %8lld %8lld %10.2f %10.2f %10.2f %10.2f %8lld %10.1f %8lld %8lld\n", s.filter.c_str(),
                  static_cast<long long>(s.poses), static_cast<long long>(s.scored), s.rmse_m, s.median_m, s.p95_m,
                  s.max_m, static_cast<long long>(s.gps_rejected), s.longest_rejection_s,
                  static_cast<long long>(s.lockouts), static_cast<long long>(s.relocalized));
    std::printf("report: %s/report.json, figures drive.png, error.png (%.1f s)\n", eo.out_dir.c_str(), r.seconds);
    return app::kExitOk;
  });
}
