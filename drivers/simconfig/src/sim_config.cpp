// The simulation's sections of the system file (sim_config.hpp): read here, then the rest of the
// file by parseSystemConfig, which also refuses a top-level key that neither reads.
#include "lcmloc/simconfig/sim_config.hpp"

#include <fmt/format.h>

#include "config_ins_sim.hpp"
#include "config_scenario.hpp"
#include "lcmloc/app/yaml_reader.hpp"

namespace lcmloc::simconfig {

// Built on the application layer (configuration, process helpers).
using namespace lcmloc::app;

SimSystemConfig parseSimSystemConfig(const std::string& yaml_text, const std::string& file) {
  SimSystemConfig cfg;
  KeyReader root(parseYamlText(yaml_text, file), file, "");  // (its keys are checked by parseSystemConfig)
  scenario_config::parseScenarioSection(root, cfg.scenario);
  scenario_config::parsePath(root, cfg.scenario.path);
  scenario_config::parseMarkers(root, cfg.scenario.markers);
  scenario_config::parseVehicle(root, cfg.scenario.vehicle);
  scenario_config::parseOdometry(root, cfg.scenario.odometry);
  scenario_config::parseMagRuler(root, cfg.scenario.magruler);
  scenario_config::parseFaults(root, cfg.scenario.faults);
  scenario_config::parseImu(root, cfg.scenario.imu);
  scenario_config::parseGps(root, cfg.scenario.gps, cfg.gps_driver);
  ins_config::parseInsSim(root, cfg.ins_sim);
  scenario_config::parseVision(root, cfg.scenario.vision);
  static_cast<SystemConfig&>(cfg) = parseSystemConfig(yaml_text, file);
  for (const auto& l : cfg.landmarks) cfg.scenario.landmarks.push_back({l.id, l.x, l.y});
  checkSampledRate(cfg.scenario.odometry.rate_hz, cfg.scenario, file, "odometry.rate_hz");
  checkSampledRate(cfg.scenario.imu.rate_hz, cfg.scenario, file, "imu.rate_hz");
  checkSampledRate(cfg.scenario.magruler.publish_rate_hz, cfg.scenario, file, "magruler.publish_rate_hz");
  return cfg;
}

SimSystemConfig loadSimSystemConfig(const std::string& path) {
  return parseSimSystemConfig(readConfigFile(path), path);
}

void checkSampledRate(double rate_hz, const sim::ScenarioConfig& sc, const std::string& file,
                      const std::string& key) {
  if (rate_hz > sc.vehicle.rate_hz)
    throw ConfigError(file, key,
                      fmt::format("{} Hz is above the ground-truth rate vehicle.rate_hz ({} Hz) the sensor samples: it "
                                  "would publish at {} Hz",
                                  rate_hz, sc.vehicle.rate_hz, sc.vehicle.rate_hz));
}

}  // namespace lcmloc::simconfig
