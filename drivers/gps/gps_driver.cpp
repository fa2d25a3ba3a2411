// lcmloc-gps's work (gps_driver.hpp).
#include "gps_driver.hpp"

#include <optional>

#include <spdlog/spdlog.h>

#include "gpsd_source.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/drivers/truth_driver.hpp"
#include "lcmloc/sim/gnss_sensors.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::gps {

int runSim(const simconfig::SimSystemConfig& cfg, bus::Bus& bus) {
  const auto& sc = cfg.scenario;
  std::optional<sim::GpsSensor> sensor;
  auto start = [&] { sensor.emplace(sc.gps, sim::componentSeed(sc.seed, "gps")); };
  start();
  const bus::LocalFrame frame(cfg.datum);
  int64_t no_fix = 0;
  drivers::TruthDriver driver(
      bus, cfg, "lcmloc-gps",
      [&](const std::string&, const lcmloc::ground_truth_t& m) {
        if (auto f = sensor->sample(drivers::toCore(m))) {
          if (!f->has_fix && no_fix++ == 0) spdlog::info("outage: no fix from utime {}", f->utime);
          bus.publish(cfg.channels.gps, drivers::toLcm(*f, frame, driver.nextSeq()));
        }
      },
      start, [&] { return app::Heartbeat::Counters{{"no_fix", no_fix}}; });
  spdlog::info("simulated receiver: {} -> {} at {} Hz, {} error {} m, {} outage(s), {} jump(s), datum ({}, {})",
               cfg.channels.ground_truth, cfg.channels.gps, sc.gps.rate_hz, sc.gps.error_model, sc.gps.error,
               sc.gps.outages.size(), sc.gps.jumps.size(), cfg.datum.latitude, cfg.datum.longitude);
  return driver.run([&] { return fmt::format("{} fixes out ({} without a fix)", driver.published(), no_fix); });
}

int runGpsd(const simconfig::SimSystemConfig& cfg, bus::Bus& bus) {
  const auto& g = cfg.gps_driver;
  GpsdSource src(g.gpsd_host, g.gpsd_port, g.time_source == "fix");
  int64_t seq = 0, no_fix = 0;
  app::Heartbeat hb(bus, cfg.channels.heartbeat, "lcmloc-gps", [&] {
    return app::Heartbeat::Counters{{"reports", src.reports()}, {"published", seq}, {"no_fix", no_fix}};
  });
  spdlog::info("gpsd at {}:{} -> {} (utime from {})", g.gpsd_host, g.gpsd_port, cfg.channels.gps,
               g.time_source);
  while (!app::stopRequested()) {
    hb.tick();
    auto fix = src.poll(100);
    if (!fix) continue;
    fix->seq = seq++;
    if (fix->fix_type < 2) ++no_fix;
    if (seq == 1)
      spdlog::info("first report: fix type {}, ({:.7f}, {:.7f})", fix->fix_type, fix->latitude, fix->longitude);
    bus.publish(cfg.channels.gps, *fix);
  }
  spdlog::info("stopping: {} gpsd reports, {} fixes out ({} without a fix)", src.reports(), seq, no_fix);
  hb.publish("stopping");
  return app::kExitOk;
}

int run(const simconfig::SimSystemConfig& cfg, bus::Bus& bus) {
  return cfg.gps_driver.source == "gpsd" ? runGpsd(cfg, bus) : runSim(cfg, bus);
}

}  // namespace lcmloc::gps
