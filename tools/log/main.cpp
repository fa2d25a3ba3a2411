// lcmloc-log: look inside LCM logs without writing code (lcmloc/logtool/command.hpp).
//   info    channels, types (by fingerprint), counts, rates, time span, seq gaps, undecodable events
//   to-csv  one channel or all, decoded to CSV with a header row named after the fields
//   cut     a time window and/or a channel subset into a new log
#include <CLI/CLI.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/logtool/command.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-log: look inside LCM logs (ours or lcm-logger's): info, to-csv, cut.\n"
               "A truncated or damaged log is read up to and past the damage, which is reported with its\n"
               "byte offset and event number (exit 3: the command's work is done with the intact events)."};
  app::CommonOptions opts;
  app::addOfflineOptions(app, opts, "system YAML file (checked when given; the log tools need no settings)");
  logtool::LogCommand command;
  logtool::addLogOptions(app, command);
  return app::runProcess(app, argc, argv, opts, "lcmloc-log", [&] {
    if (!opts.config.empty()) app::loadSystemConfig(opts.config);
    return logtool::runLogCommand(command);
  });
}
