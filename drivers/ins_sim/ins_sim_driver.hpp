#pragma once
// lcmloc-ins-sim's work: the §II simulation of the odometry/INS method (seeds/004) drives the
// vehicle along the configured motion profile on the WGS-84 ellipsoid and publishes GROUND_TRUTH,
// IMU (the paper's sensor grade) and ODOMETRY (distance increments with the scale error), paced
// by the real-time factor. Models: drivers/models (InsSim), shared with lcmloc-ins-experiment.
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::ins_sim {

/// Runs the simulation ic (start time from cfg.scenario.vehicle, channels from cfg) on bus at the
/// real-time factor (0 = as fast as possible) until it is over or a stop is requested. Returns
/// app::kExitOk.
int run(const simconfig::SimSystemConfig& cfg, const sim::InsSimConfig& ic, double factor, bus::Bus& bus);

}  // namespace lcmloc::ins_sim
