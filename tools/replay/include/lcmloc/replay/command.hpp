#pragma once
// lcmloc-replay's work after its command line: the config overrides (--filter, --shadow,
// --no-shadow), then the replay of a log (replayLog) with its summary on stdout, or the
// benchmark (runBench).
#include <string>

#include "lcmloc/app/config.hpp"
#include "lcmloc/replay/bench.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::replay {

struct CommandOptions {
  std::string input;    ///< the input log
  std::string output;   ///< the output log
  bool overwrite = false;  ///< replace an existing output
  std::string filter;   ///< overrides fusion.filter.type ("" = none)
  std::string shadow;   ///< overrides fusion.shadow: comma-separated filter types ("" = none)
  bool no_shadow = false;
  bool with_inputs = false;
  bool control = false;  ///< ReplayOptions::control
  bool one_thread = false;
  double progress_s = 2.0;  ///< [s, wall] between progress lines; 0 = none
  bool bench = false;       ///< the benchmark instead (bench_options)
  BenchOptions bench_options;
};

/// cfg with --filter, --no-shadow and --shadow applied. Throws ConfigError for an unknown filter.
simconfig::SimSystemConfig applyOverrides(simconfig::SimSystemConfig cfg, const CommandOptions& o);

/// Replays o.input into o.output (or runs the benchmark) with cfg and prints the summary.
/// Throws UsageError (exit 2) without an input or an output, for a missing input, and for an
/// existing output without o.overwrite. Returns app::kExitOk, kExitRuntimeError (the output
/// could not be written) or kExitInputDamaged.
int runCommand(const simconfig::SimSystemConfig& cfg, const CommandOptions& o);

}  // namespace lcmloc::replay
