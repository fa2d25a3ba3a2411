// lcmloc-import's options and its run after its command line (import_command.hpp).
#include "lcmloc/import/import_command.hpp"

#include <iostream>

#include <spdlog/spdlog.h>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"

namespace lcmloc::import {

void addImportOptions(CLI::App& app, ImportCommand& c) {
  app.add_option("dir", c.io.dir, "directory holding the *.csv files")->required();
  app::addOutputOption(app, c.io.out_dir, "output directory (run.lcmlog, map.csv, config.yaml); omit to check only");
  app::addOverwriteFlag(app, c.overwrite);
  app.add_option("--time-unit", c.unit, "time column unit: auto, s, us (a header time_s / time_us fixes it per file)")
      ->capture_default_str()->check(CLI::IsMember({"auto", "s", "us"}));
  app.add_option("--time-base", c.base, "absolute (Unix epoch) or relative times: auto, absolute, relative")
      ->capture_default_str()->check(CLI::IsMember({"auto", "absolute", "relative"}));
  app.add_flag("--start-at-zero", c.io.start_at_zero, "shift every time so that the earliest row is at 0");
  app.add_flag("--no-noise-fit{false}", c.io.fit_noise,
               "keep the filter's default noise (default: fitted against the ground truth when there is one)");
  app.add_option("--wheelbase", c.io.wheelbase, "L [m]: needed for speed,steering odometry (eq. 2)")
      ->check(app::positive());
  app.add_option("--filter", c.io.filter, "filter type written into config.yaml (default: from the data)");
  app.add_option("--initial-pose", c.pose, "x y theta [m m rad] (default: first ground-truth row, else 0 0 0)")
      ->expected(3);
  app.add_option("--show-refused", c.show, "list at most this many refused rows")
      ->capture_default_str()
      ->check(app::nonNegative());
  app.footer("The datum (lat/lon origin of the local frame, for GPS) and the channel names come from --config.");
}

int runImport(const app::SystemConfig& cfg, ImportCommand c) {
  app::refuseExistingOutput(c.io.out_dir, c.overwrite);
  ImportOptions& io = c.io;
  io.datum = cfg.datum;
  io.channels = cfg.channels;
  io.unit = c.unit == "s" ? TimeUnit::Seconds : c.unit == "us" ? TimeUnit::Microseconds : TimeUnit::Auto;
  io.base = c.base == "absolute" ? TimeBase::Absolute : c.base == "relative" ? TimeBase::Relative : TimeBase::Auto;
  if (c.pose.size() == 3) io.initial_pose = core::Vec3(c.pose[0], c.pose[1], c.pose[2]);
  const auto r = importDirectory(io);
  std::cout << importSummary(r, c.show);
  if (!r.usable()) {
    spdlog::error("nothing usable in '{}': no valid row in any recognised file", io.dir);
    return app::kExitRuntimeError;
  }
  if (!r.refusals.empty()) {  // the rest is imported: the exit code says the input had bad rows
    spdlog::warn("{} row(s) refused (listed above): the rest is imported; exit {} (damaged input)", r.refusals.size(),
                 app::kExitInputDamaged);
    return app::kExitInputDamaged;
  }
  return app::kExitOk;
}

}  // namespace lcmloc::import
