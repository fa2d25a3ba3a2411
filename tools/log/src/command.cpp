// lcmloc-log's options and its run after its command line (command.hpp).
#include "lcmloc/logtool/command.hpp"

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/files.hpp"

namespace lcmloc::logtool {

void addLogOptions(CLI::App& app, LogCommand& c) {
  app.require_subcommand(1);

  auto* info_cmd = app.add_subcommand("info", "channels, types, counts, rates, time span, seq gaps, undecodable events");
  info_cmd->add_option("log", c.log_path, "LCM log file")->required();
  info_cmd->callback([&c] { c.subcommand = Subcommand::Info; });

  auto* csv_cmd = app.add_subcommand("to-csv", "decode one channel (or all) to CSV, header row named after the fields");
  csv_cmd->add_option("log", c.log_path, "LCM log file")->required();
  csv_cmd->add_option("--channel,-c", c.channels, "channel regex (repeatable; default: every channel)")
      ->allow_extra_args(false);  // one regex per -c: the log path after it is no regex
  app::addOutputOption(*csv_cmd, c.output,
                          "CSV file ('-' or none: stdout) for one channel; a directory (one CHANNEL.csv each) for several");
  app::addOverwriteFlag(*csv_cmd, c.overwrite);
  csv_cmd->callback([&c] { c.subcommand = Subcommand::ToCsv; });

  auto* cut_cmd = app.add_subcommand("cut", "copy a time window and/or a channel subset into a new log");
  cut_cmd->add_option("log", c.log_path, "LCM log file")->required();
  app::addOutputOption(*cut_cmd, c.output, "new log file")->required();
  app::addOverwriteFlag(*cut_cmd, c.overwrite);
  cut_cmd->add_option("--channel,-c", c.cut.channels, "channel regex to keep (repeatable; default: all)")
      ->allow_extra_args(false);  // one regex per -c: the log path after it is no regex
  cut_cmd->add_option("--from", c.cut.from, "keep from this many seconds after the first event")
      ->check(app::nonNegative());
  cut_cmd->add_option("--to", c.cut.to, "keep up to this many seconds after the first event")
      ->check(app::nonNegative());
  cut_cmd->add_option("--from-utime", c.cut.from_utime, "keep events with log time >= this [us]");
  cut_cmd->add_option("--to-utime", c.cut.to_utime, "keep events with log time <= this [us]");
  cut_cmd->callback([&c] { c.subcommand = Subcommand::Cut; });
}

int runLogCommand(const LogCommand& c) {
  if (const std::string problem = app::fileProblem(c.log_path); !problem.empty())
    throw app::ConfigError(c.log_path, "",
                              problem == app::kNoSuchFile ? "no such log file" : problem + ": not a log file");
  if (c.subcommand == Subcommand::Info) return info(c.log_path);
  if (!c.output.empty() && c.output != "-") {
    app::refuseOutputOverInputs("--output", c.output, {c.log_path}, "input log");  // (the more useful message)
    app::refuseExistingOutput(c.output, c.overwrite);
  }
  if (c.subcommand == Subcommand::ToCsv) return toCsv(c.log_path, c.channels, c.output);
  return cut(c.log_path, c.output, c.cut);
}

}  // namespace lcmloc::logtool
