// lcmloc-ins-experiment: §II of Wang & Wang (seeds/004) as a scenario (in process, the models of
// lcmloc-ins-sim and the fusion engine of lcmloc-fusion): odometer scale-error estimate over
// time (Fig. 1) and position error of the calibrated odometry/INS against the traditional
// integration (Fig. 2), for a hard start and a gentle start. Optionally writes the sensor log of
// the first run (GROUND_TRUTH, IMU, ODOMETRY) for lcmloc-replay (lcmloc/ins_experiment/command.hpp).
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/ins_experiment/command.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-ins-experiment: odometry/INS scale calibration vs traditional integration (seeds/004 §II)"};
  app::CommonOptions opts;
  opts.config = app::configDir() + "/ins_paper.yaml";
  app::addCommonOptions(app, opts);
  ins_experiment::CommandOptions o;
  app::addOutputOption(app, o.output, "output directory (report.json, figures)")->capture_default_str();
  app.add_option("--starts", o.starts, "runs: start profiles (hard, gentle, gentle_turn, gentle_stopgo, steady)")
      ->delimiter(',')->capture_default_str();
  app.add_option("--duration", o.duration, "override ins_sim.duration [s]")
      ->check(CLI::Range(simconfig::kInsSimDuration.lo, simconfig::kInsSimDuration.hi));
  app.add_option("--seed", o.seed, "override ins_sim.seed")->check(app::seed());
  app.add_option("--calibration-stage", o.experiment.calibration_stage,
                 "dead reckoning freezes the scale estimate this long after the start [s]")
      ->capture_default_str()
      ->check(app::nonNegative());
  app.add_flag("--fixes", o.experiment.fixes,
               "three-landmark fixes: lcmloc-vision's model (config `vision`, top-level `landmarks`) "
               "re-initializes both filters; the report gives the error before/after each fix");
  app.add_option("--log", o.log, "write the sensor log of the first run (GROUND_TRUTH, IMU, ODOMETRY) to this file");
  app::addOverwriteFlag(app, o.overwrite);

  return app::runProcess(app, argc, argv, opts, "lcmloc-ins-experiment", [&] {
    return ins_experiment::runCommand(simconfig::loadSimSystemConfig(opts.config), o);
  });
}
