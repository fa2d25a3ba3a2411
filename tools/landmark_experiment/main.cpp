// lcmloc-landmark-experiment: Fig. 5 of seeds/004 §III. Monte Carlo of the three-landmark fix
// (error triangle and damped least squares) with bearings from the vision model of lcmloc-vision,
// both readings of "1000 m", vehicle at the centre and off centre, against the Cramér-Rao bound
// (lcmloc/landmark_experiment/command.hpp).
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/landmark_experiment/command.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-landmark-experiment: Fig. 5 of seeds/004 §III (three-landmark position and heading fix), "
      "Monte Carlo. Bearing noise, resolution and seed come from the `vision` section of the config; "
      "the landmarks are placed by the experiment (equilateral triangle, both readings of the distance), "
      "not taken from the config's `landmarks` map. A damaged --log is solved up to and past the damage, each "
      "damaged place reported (exit 3)."};
  app::CommonOptions opts;
  opts.config = app::configDir() + "/landmark_paper.yaml";
  app::addCommonOptions(app, opts);
  landmark_experiment::CommandOptions o;
  app.add_option("--runs", o.experiment.runs, "Monte Carlo runs per case (10000 for stable statistics)")
      ->check(CLI::Range(1, 10000000))->capture_default_str();
  app.add_option("--seed", o.seed, "override the seed (default: vision.seed, else derived from scenario.seed)")
      ->check(app::seed());
  app::addOutputOption(app, o.output, "output directory (report.json, figures)")->capture_default_str();
  app::addOverwriteFlag(app, o.overwrite);
  app.add_option("--distance", o.experiment.distance, "the paper's landmark distance [m]")
      ->check(CLI::Range(1.0, 1e6))->capture_default_str();
  app.add_option("--ins-offset", o.ins_offset, "INS position error east,north [m]")
      ->delimiter(',')->expected(2)->capture_default_str();
  app.add_option("--heading-error", o.heading_arcmin,
                 "INS heading error [arcmin], heading clockwise from north as in the paper")
      ->check(CLI::Range(-600.0, 600.0))->capture_default_str();
  app.add_option("--log", o.log,
                 "instead of the Monte Carlo: solve the VISION observations of a recorded run (e.g. "
                 "lcmloc-launcher --system config/landmark_system.yaml) against its GROUND_TRUTH, with the "
                 "config's `landmarks` map and the INS error above")
      ->check(CLI::ExistingFile);
  app.add_option("--off-centre", o.off_centre, "off-centre vehicle east,north as fractions of the circumradius")
      ->delimiter(',')->expected(2)->capture_default_str();

  return app::runProcess(app, argc, argv, opts, "lcmloc-landmark-experiment", [&] {
    return landmark_experiment::runCommand(simconfig::loadSimSystemConfig(opts.config), o);
  });
}
