// lcmloc-sim: drives the simulated vehicle along the scenario path and publishes GROUND_TRUTH,
// paced by the real-time factor; exits 0 after the final sample (--write-map FILE: the world's markers instead).
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/drivers/scenario_map.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/pacer.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-sim: simulated vehicle, publishes ground truth (GROUND_TRUTH)"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  double rtf = -1.0;
  app.add_option("--realtime-factor", rtf, "override scenario.realtime_factor (0 = as fast as possible)")
      ->check(CLI::Range(simconfig::kRealtimeFactor.lo, simconfig::kRealtimeFactor.hi));
  std::string map_out;
  app.add_option("--write-map", map_out, "write the scenario's markers as a map file (fusion.map_file) and exit");
  return app::runProcess(app, argc, argv, opts, "lcmloc-sim", [&] {
    const auto cfg = simconfig::loadSimSystemConfig(opts.config);
    if (!map_out.empty()) {
      drivers::writeScenarioMap(cfg, map_out);
      return app::kExitOk;
    }
    const auto& sc = cfg.scenario;
    const double factor = rtf >= 0.0 ? rtf : sc.realtime_factor;

    const sim::Path path(sc.path);
    const double stop_at = sim::stopArcLength(sc, path.length());
    sim::VehicleSim vehicle(sc.vehicle, path, stop_at, sim::componentSeed(sc.seed, "vehicle"));

    bus::Bus bus(opts.lcm_url);
    int64_t seq = 0;
    app::Heartbeat hb(bus, cfg.channels.heartbeat, "lcmloc-sim", [&] { return app::Heartbeat::Counters{{"published", seq}}; });
    hb.tick();
    spdlog::info("scenario '{}' seed {}: {:.1f} m of path at {:.1f} m/s, real-time factor {}",
                 sc.name, sc.seed, stop_at, sc.vehicle.speed, factor);

    app::Pacer pacer(factor);
    auto publish = [&](const sim::TruthState& s) {
      if (!pacer.waitUntil(s.utime, [&] { hb.tick(); })) return false;
      bus.publish(cfg.channels.ground_truth, drivers::toLcm(s, seq++));
      return true;
    };
    bool running = publish(vehicle.state());
    while (running && !vehicle.finished()) running = publish(vehicle.step());

    const auto& s = vehicle.state();
    if (!running)
      spdlog::info("stopped by signal {} after {} samples", app::stopSignal(), seq);
    else
      spdlog::info("run over: {} samples, {:.2f} m travelled, final pose ({:.3f}, {:.3f}, {:.3f})",
                   seq, s.distance, s.x, s.y, s.heading);
    hb.publish("stopping");
    return app::kExitOk;
  });
}
