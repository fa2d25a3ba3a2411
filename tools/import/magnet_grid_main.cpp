// lcmloc-magnet-grid: imports the magnet-grid runs (encoder counts + reed byte) and replays them
// with the gated ruler UKF: gate and innovation statistics, track over the grid
// (lcmloc/import/magnet_grid_command.hpp).
#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/import/magnet_grid_command.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-magnet-grid: the magnet-grid runs of ../shared/data/magnet_grid_ecn. For each run: import (encoder "
      "counts -> differential-drive ODOMETRY, reed byte -> one MAGRULER detection per magnet pass with its lateral "
      "offset, the 55 mm grid -> map.csv, config.yaml), replay with the gated ruler UKF (and a dead-reckoning "
      "shadow), write OUT/<run>/report.json and track.png; OUT/summary.json over the runs. docs/magnet_grid.md."};
  app::CommonOptions opts;
  app::addOfflineOptions(app, opts,
                            "system YAML file (checked when given; unused otherwise: each run writes its own config.yaml)");
  import::MagnetGridCommand c;
  c.data = LCMLOC_MAGNET_GRID_DIR;
  app.add_option("--data", c.data, "data directory (<run>.txt files)")->capture_default_str();
  app.add_option("--run", c.runs, "run name(s) (default: all six) or paths to run files");
  app::addOutputOption(app, c.output, "output directory (OUT/<run>/..., OUT/summary.json)")->capture_default_str();
  app::addOverwriteFlag(app, c.overwrite);
  app.add_flag("--import-only", c.import_only,
               "only write OUT/<run>/run.lcmlog, map.csv, config.yaml (for lcmloc-replay)");
  app.add_option("--bit0", c.grid.bit0, "side of reed bit 0: right or left")->capture_default_str()
      ->check(CLI::IsMember({"right", "left"}));
  app.add_option("--filter", c.grid.filter, "filter type of config.yaml")->capture_default_str();
  app.add_option("--grid-angle", c.grid_angle,
                 "grid axes vs the start heading [rad] (default 0; pi/4 for diagonal45degrees, which starts at 45 "
                 "degrees to the grid)");
  app.add_option("--pv-diag", c.pv_diag, "detection noise: range [m^2], bearing [rad^2]")->expected(2);
  app.add_option("--pw-diag", c.pw_diag, "process noise per pw_distance: x, y [m^2], theta [rad^2]")->expected(3);
  app.add_option("--pw-turn", c.grid.pw_turn, "heading variance per radian turned [rad^2/rad]")->capture_default_str();
  app.add_option("--reach", c.grid.reach, "association window beyond the reed row [m]")->capture_default_str();

  return app::runProcess(app, argc, argv, opts, "lcmloc-magnet-grid", [&]() -> int {
    if (!opts.config.empty()) app::loadSystemConfig(opts.config);
    return import::runMagnetGridCommand(c);
  });
}
