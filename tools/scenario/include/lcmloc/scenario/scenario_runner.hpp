#pragma once
// In-process scenario: the same world and sensor models the driver processes wrap, stepped in
// the same order, feeding one or more filters through the fusion engine. Used by the scenario
// tests, the Monte Carlo and the GPS experiment (no LCM, deterministic for a given config and
// seed). Scored with the scoring library (lcmloc/core/scoring.hpp).
#include <map>
#include <string>
#include <vector>

#include "lcmloc/core/engine.hpp"
#include "lcmloc/sim/gnss_sensors.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::scenario {

using sim::GpsFixSample;
using sim::ScenarioConfig;
using sim::TruthState;

struct TrackPoint {
  int64_t utime = 0;
  core::Pose truth;
  core::FilterState estimate;
};

struct ScenarioFilterResult {
  std::string filter;
  std::vector<TrackPoint> track;               ///< one point per odometry step
  std::vector<core::GateDecision> decisions;   ///< one per ruler measurement
  std::vector<bool> decision_is_fault;         ///< parallel to decisions
  int faults_total = 0, faults_rejected = 0, valid_rejected = 0, accepted = 0, rejected = 0;
  double rmse_m = 0, max_error_m = 0, final_error_m = 0;
  double mean_nees = 0;                        ///< mean NEES of (x, y, theta) over the track
  bool locked_out = false;                     ///< ended with >= lockout_rejections rejections in a row, or ever reported LOCKOUT
  int lockout_events = 0;
};

struct ScenarioResult {
  core::MarkerMap map;
  std::vector<TruthState> truth;
  std::vector<GpsFixSample> gps;               ///< fixes fed to the filters (when gps.enabled)
  std::vector<ScenarioFilterResult> filters;   ///< in the order requested
};

/// Runs the scenario once with each filter config (each in its own engine, same sensor data).
/// output_every: core::EngineConfig::output_every of the engines (the track then holds the
/// published states only).
ScenarioResult runScenario(const ScenarioConfig& scenario,
                           const std::vector<core::FilterConfig>& filters, int output_every = 1);

}  // namespace lcmloc::scenario
