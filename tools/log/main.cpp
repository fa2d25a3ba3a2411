// lcmloc-log: look inside LCM logs without writing code (the subcommands: lcmloc_logtool).
//   info    channels, types (by fingerprint), counts, rates, time span, seq gaps, undecodable events
//   to-csv  one channel or all, decoded to CSV with a header row named after the fields
//   cut     a time window and/or a channel subset into a new log
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/logtool/log_tool.hpp"

using namespace lcmloc;
using logtool::CutOptions;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-log: look inside LCM logs (ours or lcm-logger's): info, to-csv, cut.\n"
               "A truncated or damaged log is read up to and past the damage, which is reported with its\n"
               "byte offset and event number (exit 3: the command's work is done with the intact events)."};
  common::CommonOptions opts;
  common::addOfflineOptions(app, opts, "system YAML file (checked when given; the log tools need no settings)");
  app.require_subcommand(1);
  std::string log_path, output;
  std::vector<std::string> channels;
  CutOptions cut_opts;

  auto* info_cmd = app.add_subcommand("info", "channels, types, counts, rates, time span, seq gaps, undecodable events");
  info_cmd->add_option("log", log_path, "LCM log file")->required();

  auto* csv_cmd = app.add_subcommand("to-csv", "decode one channel (or all) to CSV, header row named after the fields");
  csv_cmd->add_option("log", log_path, "LCM log file")->required();
  csv_cmd->add_option("--channel,-c", channels, "channel regex (repeatable; default: every channel)")
      ->allow_extra_args(false);  // one regex per -c: the log path after it is no regex
  bool overwrite = false;
  common::addOutputOption(*csv_cmd, output,
                          "CSV file ('-' or none: stdout) for one channel; a directory (one CHANNEL.csv each) for several");
  common::addOverwriteFlag(*csv_cmd, overwrite);

  auto* cut_cmd = app.add_subcommand("cut", "copy a time window and/or a channel subset into a new log");
  cut_cmd->add_option("log", log_path, "LCM log file")->required();
  common::addOutputOption(*cut_cmd, output, "new log file")->required();
  common::addOverwriteFlag(*cut_cmd, overwrite);
  cut_cmd->add_option("--channel,-c", cut_opts.channels, "channel regex to keep (repeatable; default: all)")
      ->allow_extra_args(false);  // one regex per -c: the log path after it is no regex
  cut_cmd->add_option("--from", cut_opts.from, "keep from this many seconds after the first event")
      ->check(lcmloc::common::nonNegative());
  cut_cmd->add_option("--to", cut_opts.to, "keep up to this many seconds after the first event")
      ->check(lcmloc::common::nonNegative());
  cut_cmd->add_option("--from-utime", cut_opts.from_utime, "keep events with log time >= this [us]");
  cut_cmd->add_option("--to-utime", cut_opts.to_utime, "keep events with log time <= this [us]");

  return common::runProcess(app, argc, argv, opts, "lcmloc-log", [&] {
    if (!opts.config.empty()) common::loadSystemConfig(opts.config);
    if (const std::string problem = common::fileProblem(log_path); !problem.empty())
      throw common::ConfigError(log_path, "", problem == common::kNoSuchFile ? "no such log file" : problem + ": not a log file");
    if (info_cmd->parsed()) return logtool::info(log_path);
    if (!output.empty() && output != "-") {
      common::refuseOutputOverInputs("--output", output, {log_path}, "input log");  // (the more useful message)
      common::refuseExistingOutput(output, overwrite);
    }
    if (csv_cmd->parsed()) return logtool::toCsv(log_path, channels, output);
    return logtool::cut(log_path, output, cut_opts);
  });
}
