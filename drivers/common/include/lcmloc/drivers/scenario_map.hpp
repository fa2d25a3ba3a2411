#pragma once
// The map of the simulated world: the scenario's magnetic markers along its path, as the fusion
// daemon reads a map (fusion.map_file, an id,x,y CSV). The daemon takes its map from a file
// only; `lcmloc-sim --write-map FILE` writes this one for a simulated run.
#include <string>

#include "lcmloc/core/types.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::drivers {

/// The markers the simulated world has (sim::makeMarkerMap over the scenario's path).
core::MarkerMap scenarioMap(const simconfig::SimSystemConfig& cfg);
/// Writes scenarioMap(cfg) to path (csv::writeMap: every coordinate as the shortest text that
/// reads back to the same double, so a replay with the file computes what one with the world's
/// own markers would). Throws std::runtime_error.
void writeScenarioMap(const simconfig::SimSystemConfig& cfg, const std::string& path);

}  // namespace lcmloc::drivers
