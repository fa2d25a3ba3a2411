#pragma once
// lcmloc-gps-experiment's tables on stdout.
#include <string>
#include <vector>

#include "lcmloc/gps_experiment/monte_carlo.hpp"

namespace lcmloc::gps_experiment {

/// The filter configs of the given types, each on top of base (fusion.filter). Throws ConfigError.
std::vector<core::FilterConfig> filterConfigs(const std::vector<std::string>& types, const core::FilterConfig& base);
/// The paper's run: convergence, steady RMSE and max, the raw GPS RMSE, rejections, lock-outs.
void printPaperRun(const Result& r, const std::string& dir, bool plotted);
/// The steady-state runs: per GPS rate and filter, runs settled, RMSE median and p95, settling
/// time median and max, mean NEES, runs with a lock-out.
void printMonteCarlo(const McResult& m, const MonteCarloOptions& opt, const std::string& dir);

}  // namespace lcmloc::gps_experiment
