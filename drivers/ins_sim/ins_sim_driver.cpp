// lcmloc-ins-sim's work (ins_sim_driver.hpp).
#include "ins_sim_driver.hpp"

#include <spdlog/spdlog.h>

#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/pacer.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/sim/ins_sim.hpp"

namespace lcmloc::ins_sim {

int run(const simconfig::SimSystemConfig& cfg, const sim::InsSimConfig& ic, double factor, bus::Bus& bus) {
  sim::InsSim sim(ic, cfg.scenario.vehicle.start_utime);
  int64_t truth_seq = 0, imu_seq = 0, odo_seq = 0;
  app::Heartbeat hb(bus, cfg.channels.heartbeat, "lcmloc-ins-sim", [&] {
    return app::Heartbeat::Counters{{"truth", truth_seq}, {"imu", imu_seq}, {"odometry", odo_seq}};
  });
  hb.tick();
  spdlog::info("ins_sim seed {}: {:.0f} s, profile {} (start {}), {} Hz, odometry every {} sample(s), "
               "real-time factor {}",
               ic.seed, ic.duration, ic.profile, ic.start, ic.rate_hz, ic.odometry_divider, factor);
  app::Pacer pacer(factor);
  bool running = pacer.waitUntil(cfg.scenario.vehicle.start_utime, [&] { hb.tick(); });
  if (running) bus.publish(cfg.channels.ground_truth, drivers::toLcm(sim.initial().truth, truth_seq++));
  sim::InsSimStep s;
  double last_report = 0.0;
  while (running && !sim.finished()) {
    s = sim.step();
    if (!pacer.waitUntil(s.truth.utime, [&] { hb.tick(); })) {
      running = false;
      break;
    }
    // Odometry (rank before IMU at equal utime in the fusion engine) then IMU then truth.
    if (s.odometry) bus.publish(cfg.channels.odometry, drivers::toLcm(*s.odometry, odo_seq++));
    if (s.imu) bus.publish(cfg.channels.imu, drivers::toLcm(*s.imu, imu_seq++));
    bus.publish(cfg.channels.ground_truth, drivers::toLcm(s.truth, truth_seq++));
    if (sim.time() - last_report >= 600.0) {
      last_report = sim.time();
      spdlog::info("t = {:.0f} s, {:.1f} km travelled", sim.time(), s.truth.distance / 1000.0);
    }
  }
  if (!running) {
    spdlog::info("stopped by signal {} at t = {:.1f} s", app::stopSignal(), sim.time());
    hb.publish("stopping");
    return app::kExitOk;
  }
  spdlog::info("run over: {:.0f} s, {:.2f} km, {} IMU samples, {} odometry increments", sim.time(),
               s.truth.distance / 1000.0, imu_seq, odo_seq);
  hb.publish("stopping");
  return app::kExitOk;
}

}  // namespace lcmloc::ins_sim
