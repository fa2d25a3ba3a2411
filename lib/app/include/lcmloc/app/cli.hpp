#pragma once
// The command line every lcmloc program shares: --config, --lcm-url, --log-level, -o/--output,
// --overwrite, --version, validators for numeric options, and runProcess, which parses the
// command line and turns what the program's body throws into an exit code (exit_codes.hpp).
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

#include "lcmloc/app/exit_codes.hpp"

namespace lcmloc::app {

/// The project's version (CMake's project(VERSION)), which --version prints after the program's name.
std::string version();

struct CommonOptions {
  std::string config;     ///< scenario/system YAML file
  std::string lcm_url;    ///< LCM provider URL
  std::string log_level = "info";
};

/// Adds --config, --lcm-url, --log-level to app, with defaults filled into opts.
void addCommonOptions(CLI::App& app, CommonOptions& opts);
/// The offline tools' version (they read and write files only): --config with the tool's own
/// meaning and no default (opts.config stays empty unless given), --lcm-url accepted for
/// uniformity with the processes on the bus and unused, --log-level. Returns the --config option.
CLI::Option* addOfflineOptions(CLI::App& app, CommonOptions& opts, const std::string& config_help);

/// Validators for numeric options with a short message (CLI11's PositiveNumber and
/// NonNegativeNumber print the whole range of a double, 300 digits). NaN and Inf are refused
/// for every floating-point option by runProcess.
CLI::Validator positive();     ///< > 0
CLI::Validator nonNegative();  ///< >= 0
/// A wall-clock duration [s] in [0, 86400]: a day at most (1e300 s overflowed the clock's
/// deadline arithmetic). Combine with positive() where 0 is not allowed.
CLI::Validator wallSeconds();
CLI::Validator seed();         ///< an unsigned 64-bit integer, without a sign ("-1" is not 2^64 - 1)

/// -o,--output: where the program writes (a file, or a directory where it writes several).
CLI::Option* addOutputOption(CLI::App& app, std::string& path, const std::string& help);
/// --overwrite: replace an existing output (without it, refuseExistingOutput refuses it).
CLI::Option* addOverwriteFlag(CLI::App& app, bool& overwrite);

/// Parses the command line and runs body(), turning exceptions into one clear error line and
/// an exit code (ConfigError, UsageError -> 2, anything else -> 1). A bad command line exits 2
/// with CLI11's message. Adds --version (prints "process_name version()", exit 0) and the exit
/// codes as a footer of --help (exit 0) to app and its subcommands. Returns the exit code.
int runProcess(CLI::App& app, int argc, char** argv, const CommonOptions& opts,
               const std::string& process_name, const std::function<int()>& body);

}  // namespace lcmloc::app
