#include "lcmloc/drivers/scenario_map.hpp"

#include "lcmloc/app/csv.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::common {

core::MarkerMap scenarioMap(const SimSystemConfig& cfg) {
  return models::makeMarkerMap(models::Path(cfg.scenario.path), cfg.scenario.markers);
}

void writeScenarioMap(const SimSystemConfig& cfg, const std::string& path) { csv::writeMap(path, scenarioMap(cfg)); }

}  // namespace lcmloc::common
