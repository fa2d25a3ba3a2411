#pragma once
// Config sections of the simulated world and its sensors, and of lcmloc-gps's source:
// `scenario`, `path`, `markers`, `vehicle`, `odometry`, `magruler`, `faults`, `imu`, `gps` and
// `vision`. Internal to drivers/simconfig/src (called from sim_config.cpp, in the file's order).
#include <vector>

#include "lcmloc/app/yaml_reader.hpp"
#include "lcmloc/sim/scenario_config.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::simconfig::scenario_config {

void parseScenarioSection(app::KeyReader& root, sim::ScenarioConfig& s);
void parsePath(app::KeyReader& root, sim::PathConfig& p);
void parseMarkers(app::KeyReader& root, sim::MarkerLayout& m);
void parseVehicle(app::KeyReader& root, sim::VehicleConfig& v);
void parseOdometry(app::KeyReader& root, sim::OdometrySensorConfig& o);
void parseMagRuler(app::KeyReader& root, sim::MagRulerConfig& m);
void parseImu(app::KeyReader& root, sim::ImuSensorConfig& m);
/// `gps`: the simulated receiver's model and the driver's source (sim or gpsd).
void parseGps(app::KeyReader& root, sim::GpsSensorConfig& g, GpsDriverConfig& d);
void parseFaults(app::KeyReader& root, std::vector<sim::FaultConfig>& faults);
/// `vision`: the simulated bearing sensor (seeds/004 §III).
void parseVision(app::KeyReader& root, sim::VisionSensorConfig& v);

}  // namespace lcmloc::simconfig::scenario_config
