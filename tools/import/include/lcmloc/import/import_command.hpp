#pragma once
// lcmloc-import as a library: its options and its run (the program is a thin main,
// tools/import/import_main.cpp). A directory of CSV files -> an LCM log, the map and a config for
// lcmloc-replay (import.hpp).
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/import/import.hpp"

namespace lcmloc::import {

struct ImportCommand {
  ImportOptions io;                 ///< dir, out_dir, start_at_zero, wheelbase, filter (the rest: from below)
  bool overwrite = false;           ///< replace an existing output directory
  std::string unit = "auto";        ///< --time-unit: auto, s, us
  std::string base = "auto";        ///< --time-base: auto, absolute, relative
  std::vector<double> pose;         ///< --initial-pose x y theta (empty: the default)
  int show = 30;                    ///< --show-refused: list at most this many refused rows
};

/// lcmloc-import's options (all but the common ones: --config, --log-level) and its help footer
/// into c.
void addImportOptions(CLI::App& app, ImportCommand& c);

/// Imports c.io.dir with the datum and channel names of cfg and prints the summary on stdout.
/// Throws UsageError (exit 2) for an existing output without c.overwrite (before anything is
/// read) and ConfigError for a bad option; returns app::kExitOk, or kExitRuntimeError when
/// nothing usable was read.
int runImport(const app::SystemConfig& cfg, ImportCommand c);

}  // namespace lcmloc::import
