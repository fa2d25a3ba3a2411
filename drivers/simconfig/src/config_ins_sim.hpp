#pragma once
// The `ins_sim` section: the INS simulator of the odometry/INS/vision method (seeds/004).
// Internal to drivers/simconfig/src (called from sim_config.cpp).
#include "lcmloc/app/yaml_reader.hpp"
#include "lcmloc/sim/ins_sim.hpp"

namespace lcmloc::simconfig::ins_config {

void parseInsSim(app::KeyReader& root, sim::InsSimConfig& c);

}  // namespace lcmloc::simconfig::ins_config
