#include "lcmloc/drivers/scenario_map.hpp"

#include "lcmloc/app/csv.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::drivers {

// Built on the application layer (configuration, process helpers).
using namespace lcmloc::app;

core::MarkerMap scenarioMap(const simconfig::SimSystemConfig& cfg) {
  return sim::makeMarkerMap(sim::Path(cfg.scenario.path), cfg.scenario.markers);
}

void writeScenarioMap(const simconfig::SimSystemConfig& cfg, const std::string& path) { csv::writeMap(path, scenarioMap(cfg)); }

}  // namespace lcmloc::drivers
