#pragma once
// §3 of the time-varying EKF paper (seeds/002) as a scenario: GPS with a +-5 m error, the filter
// starts at (0, 0) while the truth starts at (150, 50). Runs the scenario in process (the same
// models the driver processes wrap) and measures convergence time and steady-state error
// against the raw GPS error.
#include <cstdint>
#include <string>
#include <vector>

#include "lcmloc/scenario/scenario_runner.hpp"

namespace lcmloc::gps_experiment {

struct Options {
  double converged_m = 5.0;   ///< converged when the error stays below this ...
  double hold_s = 5.0;        ///< ... for at least this long [s]
};

struct FilterSummary {
  std::string filter;
  double convergence_s = -1;  ///< first time after which the error stayed < converged_m for hold_s (-1: never)
  double steady_rmse_m = 0;   ///< position RMSE after convergence (meaningless unless converged())
  double steady_max_m = 0;
  double gps_rmse_m = 0;      ///< raw GPS error over the same period (fixes with a fix)
  int gps_accepted = 0, gps_rejected = 0, lockouts = 0;
  bool converged() const { return convergence_s >= 0; }
};

struct Result {
  scenario::ScenarioResult scenario;
  std::vector<FilterSummary> filters;
  double gps_rmse_all_m = 0;  ///< raw GPS RMSE over the whole run
};

/// The settling time of a track: the start of the first stretch of at least opt.hold_s with
/// the position error below opt.converged_m, or of such a stretch that lasts to the end of the
/// run (-1: none).
int64_t settledFrom(const std::vector<scenario::TrackPoint>& track, const Options& opt);

Result run(const sim::ScenarioConfig& sc, const std::vector<core::FilterConfig>& filters,
           const Options& opt);

/// report.json + data files + plot.gp + fig1a_tracks.png, fig1b_error.png (gnuplot) in dir.
/// Returns false if gnuplot failed or is missing (the report is written anyway).
bool writeReport(const Result& r, const Options& opt, const std::string& dir);

}  // namespace lcmloc::gps_experiment
