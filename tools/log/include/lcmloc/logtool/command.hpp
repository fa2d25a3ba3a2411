#pragma once
// lcmloc-log as a library: its options (the subcommands info, to-csv and cut) and its run (the
// program is a thin main, tools/log/main.cpp).
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "lcmloc/logtool/log_tool.hpp"

namespace lcmloc::logtool {

enum class Subcommand { Info, ToCsv, Cut };

struct LogCommand {
  Subcommand subcommand = Subcommand::Info;  ///< the one given on the command line
  std::string log_path;                      ///< the input log
  std::string output;                        ///< to-csv: CSV file, "-"/"" stdout or a directory; cut: new log
  bool overwrite = false;                    ///< replace an existing output
  std::vector<std::string> channels;         ///< to-csv: channel regexes (none: every channel)
  CutOptions cut;                            ///< cut: channels and time window
};

/// lcmloc-log's subcommands and their options (all but the common ones: --config, --log-level)
/// into c; exactly one subcommand is required, and the one parsed is stored in c.subcommand.
void addLogOptions(CLI::App& app, LogCommand& c);

/// Runs the subcommand c.subcommand. Throws app::ConfigError for a missing or unreadable log
/// and UsageError (exit 2) for an output over the log or an existing output without
/// c.overwrite; returns app::kExitOk or app::kExitInputDamaged (log_tool.hpp).
int runLogCommand(const LogCommand& c);

}  // namespace lcmloc::logtool
