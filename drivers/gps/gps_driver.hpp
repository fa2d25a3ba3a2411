#pragma once
// lcmloc-gps's work: GNSS fixes on the GPS channel from one of two sources (gps.source):
//   sim   GROUND_TRUTH -> GpsSensor (drivers/models: error, outages, jumps) -> lat/lon about
//         the datum (GeographicLib LocalCartesian) -> GPS
//   gpsd  a real receiver (or gpsfake) through libgps -> GPS
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::gps {

/// The simulated receiver: a fix per GROUND_TRUTH sample due, until a stop is requested.
int runSim(const simconfig::SimSystemConfig& cfg, bus::Bus& bus);
/// gpsd's reports as they come, until a stop is requested. Throws GpsdError.
int runGpsd(const simconfig::SimSystemConfig& cfg, bus::Bus& bus);
/// runGpsd or runSim, as cfg.gps_driver.source says. Returns app::kExitOk.
int run(const simconfig::SimSystemConfig& cfg, bus::Bus& bus);

}  // namespace lcmloc::gps
