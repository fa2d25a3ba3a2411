#pragma once
// lcmloc-magnet-grid's work after its command line: for each run, the import
// (importMagnetGrid) and, unless import_only, the replay with the gated ruler UKF
// (runMagnetGrid); a line per run on stdout and OUT/summary.json over the runs.
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/import/magnet_grid.hpp"

namespace lcmloc::import {

struct MagnetGridCommand {
  std::string data;                   ///< data directory (<run>.txt files)
  std::vector<std::string> runs;      ///< run names or paths to run files (empty: all six)
  std::string output = "out/magnet_grid";  ///< output directory: OUT/<run>/..., OUT/summary.json
  bool overwrite = false;             ///< replace the files of an output directory that is not empty
  bool import_only = false;           ///< only OUT/<run>/run.lcmlog, map.csv, config.yaml
  std::optional<double> grid_angle;   ///< [rad] (default 0; pi/4 for diagonal45degrees)
  std::vector<double> pv_diag;        ///< range [m^2], bearing [rad^2] (empty: the default)
  std::vector<double> pw_diag;        ///< x, y [m^2], theta [rad^2] per pw_distance (empty: the default)
  MagnetGridOptions grid;             ///< bit0, filter, pw_turn, reach (the rest is set per run)
};

/// Throws UsageError (an existing output without overwrite, a missing run file), ConfigError
/// (a run given twice). Returns app::kExitOk.
int runMagnetGridCommand(const MagnetGridCommand& c);

}  // namespace lcmloc::import
