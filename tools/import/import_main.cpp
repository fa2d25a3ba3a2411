// lcmloc-import: a directory of CSV files -> an LCM log, the map and a config for lcmloc-replay.
#include <iostream>

#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/import/import.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-import: imports a directory of CSV files (odometry, landmarks, beacons, gps, ground truth, map; one "
      "header row each, recognised by the header, see docs/import_formats.md) into OUT/run.lcmlog (ODOMETRY, "
      "LANDMARKS, BEACONS, GPS, GROUND_TRUTH), OUT/map.csv and OUT/config.yaml for lcmloc-replay. Refused rows are "
      "listed with file, line and reason. Exit 1 when nothing usable was read."};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);
  import::ImportOptions io;
  std::string unit = "auto", base = "auto";
  std::vector<double> pose;
  int show = 30;
  app.add_option("dir", io.dir, "directory holding the *.csv files")->required();
  bool overwrite = false;
  common::addOutputOption(app, io.out_dir, "output directory (run.lcmlog, map.csv, config.yaml); omit to check only");
  common::addOverwriteFlag(app, overwrite);
  app.add_option("--time-unit", unit, "time column unit: auto, s, us (a header time_s / time_us fixes it per file)")
      ->capture_default_str()->check(CLI::IsMember({"auto", "s", "us"}));
  app.add_option("--time-base", base, "absolute (Unix epoch) or relative times: auto, absolute, relative")
      ->capture_default_str()->check(CLI::IsMember({"auto", "absolute", "relative"}));
  app.add_flag("--start-at-zero", io.start_at_zero, "shift every time so that the earliest row is at 0");
  app.add_option("--wheelbase", io.wheelbase, "L [m]: needed for speed,steering odometry (eq. 2)")
      ->check(lcmloc::common::positive());
  app.add_option("--filter", io.filter, "filter type written into config.yaml (default: from the data)");
  app.add_option("--initial-pose", pose, "x y theta [m m rad] (default: first ground-truth row, else 0 0 0)")
      ->expected(3);
  app.add_option("--show-refused", show, "list at most this many refused rows")
      ->capture_default_str()
      ->check(lcmloc::common::nonNegative());
  app.footer("The datum (lat/lon origin of the local frame, for GPS) and the channel names come from --config.");

  return common::runProcess(app, argc, argv, opts, "lcmloc-import", [&]() -> int {
    const auto cfg = common::loadSystemConfig(opts.config);
    common::refuseExistingOutput(io.out_dir, overwrite);
    io.datum = cfg.datum;
    io.channels = cfg.channels;
    io.unit = unit == "s" ? import::TimeUnit::Seconds : unit == "us" ? import::TimeUnit::Microseconds
                                                                   : import::TimeUnit::Auto;
    io.base = base == "absolute" ? import::TimeBase::Absolute
              : base == "relative" ? import::TimeBase::Relative : import::TimeBase::Auto;
    if (pose.size() == 3) io.initial_pose = core::Vec3(pose[0], pose[1], pose[2]);
    const auto r = import::importDirectory(io);
    std::cout << import::importSummary(r, show);
    if (!r.usable()) {
      spdlog::error("nothing usable in '{}': no valid row in any recognised file", io.dir);
      return common::kExitRuntimeError;
    }
    return common::kExitOk;
  });
}
