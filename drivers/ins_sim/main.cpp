// lcmloc-ins-sim: the §II simulation of the odometry/INS method (seeds/004), publishing
// GROUND_TRUTH, IMU and ODOMETRY paced by the real-time factor (ins_sim_driver.hpp).
#include "ins_sim_driver.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-ins-sim: odometry/INS simulation (seeds/004 §II), publishes GROUND_TRUTH, IMU, ODOMETRY"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  double rtf = -1.0, duration = 0.0;
  uint64_t seed = 0;
  app.add_option("--realtime-factor", rtf, "override scenario.realtime_factor (0 = as fast as possible)")
      ->check(CLI::Range(simconfig::kRealtimeFactor.lo, simconfig::kRealtimeFactor.hi));
  app.add_option("--duration", duration, "override ins_sim.duration [s]")
      ->check(CLI::Range(simconfig::kInsSimDuration.lo, simconfig::kInsSimDuration.hi));
  app.add_option("--seed", seed, "override ins_sim.seed")->check(app::seed());

  return app::runProcess(app, argc, argv, opts, "lcmloc-ins-sim", [&] {
    const auto cfg = simconfig::loadSimSystemConfig(opts.config);
    auto ic = cfg.ins_sim;
    if (duration > 0) ic.duration = duration;
    if (seed) ic.seed = seed;
    bus::Bus bus(opts.lcm_url);
    return ins_sim::run(cfg, ic, rtf >= 0.0 ? rtf : cfg.scenario.realtime_factor, bus);
  });
}
