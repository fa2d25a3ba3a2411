#pragma once
// The `ins_sim` section: the INS simulator of the odometry/INS/vision method (seeds/004).
// Internal to drivers/simconfig/src (called from sim_config.cpp).
#include "lcmloc/app/yaml_reader.hpp"
#include "lcmloc/sim/ins_sim.hpp"

namespace lcmloc::common::ins_config {

void parseInsSim(KeyReader& root, models::InsSimConfig& c);

}  // namespace lcmloc::common::ins_config
