// lcmloc-import: a directory of CSV files -> an LCM log, the map and a config for lcmloc-replay
// (lcmloc/import/import_command.hpp).
#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/import/import_command.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-import: imports a directory of CSV files (odometry, landmarks, beacons, gps, ground truth, imu, map; "
      "one header row each, recognised by its column names, see docs/import_formats.md) into OUT/run.lcmlog "
      "(ODOMETRY, LANDMARKS, BEACONS, GPS, GROUND_TRUTH, IMU), OUT/map.csv and OUT/config.yaml for lcmloc-replay. "
      "Refused rows are listed with file, line and reason. Exit 2 when a *.csv file is none of the formats (the "
      "formats are listed), 1 when nothing usable was read."};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  import::ImportCommand command;
  import::addImportOptions(app, command);
  return app::runProcess(app, argc, argv, opts, "lcmloc-import", [&]() -> int {
    return import::runImport(app::loadSystemConfig(opts.config), command);
  });
}
