#pragma once
// Config sections of the simulated world and its sensors, and of lcmloc-gps's source:
// `scenario`, `path`, `markers`, `vehicle`, `odometry`, `magruler`, `faults`, `imu`, `gps` and
// `vision`. Internal to drivers/simconfig/src (called from sim_config.cpp, in the file's order).
#include <vector>

#include "lcmloc/app/yaml_reader.hpp"
#include "lcmloc/sim/scenario_config.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::common::scenario_config {

void parseScenarioSection(KeyReader& root, models::ScenarioConfig& s);
void parsePath(KeyReader& root, models::PathConfig& p);
void parseMarkers(KeyReader& root, models::MarkerLayout& m);
void parseVehicle(KeyReader& root, models::VehicleConfig& v);
void parseOdometry(KeyReader& root, models::OdometrySensorConfig& o);
void parseMagRuler(KeyReader& root, models::MagRulerConfig& m);
void parseImu(KeyReader& root, models::ImuSensorConfig& m);
/// `gps`: the simulated receiver's model and the driver's source (sim or gpsd).
void parseGps(KeyReader& root, models::GpsSensorConfig& g, GpsDriverConfig& d);
void parseFaults(KeyReader& root, std::vector<models::FaultConfig>& faults);
/// `vision`: the simulated bearing sensor (seeds/004 §III).
void parseVision(KeyReader& root, models::VisionSensorConfig& v);

}  // namespace lcmloc::common::scenario_config
