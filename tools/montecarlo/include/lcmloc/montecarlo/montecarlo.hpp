#pragma once
// Monte Carlo of the magnetic-ruler scenario (lcmloc-montecarlo): runs the scenario N times
// (seed = base + i) in process with each requested filter (scenario::runScenario) and writes
// per-filter lock-out rate, RMSE median / p95, faults and valid markers rejected to a JSON
// report. Options vary the marker layout and the process noise without editing the config.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace lcmloc::montecarlo {

struct Options {
  std::string config;  ///< empty: built-in defaults (the paper's scenario)
  int runs = 200;
  std::optional<uint64_t> seed_base;  ///< none: the config's seed
  double scale_error = 0.01;
  double steering_bias_deg = 0.5;
  bool no_faults = false;
  double marker_spacing = 0.0;  ///< > 0: markers every this many metres over the configured span
  std::vector<double> pw_diag;  ///< 3 values: replaces fusion.filter.pw_diag
  std::string filters = "ukf_gated,ukf_calib";
  std::string out = "out/montecarlo/report.json";
  bool overwrite = false;  ///< --overwrite: replace an existing report
};

/// The command-line options of lcmloc-montecarlo (all but the common ones) into o.
void addOptions(CLI::App& app, Options& o);

/// Runs the Monte Carlo and writes the report to o.out. Returns the exit code (1 when stopped
/// before all runs were done); throws app::ConfigError on a bad option or config.
int run(const Options& o);

}  // namespace lcmloc::montecarlo
