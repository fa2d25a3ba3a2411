// lcmloc-fault-injector: publishes the configured faulty marker detections on MAGRULER_FAULT
// (as the ruler driver would) and announces each one on FAULT_EVENTS.
#include <spdlog/spdlog.h>

#include <optional>

#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/drivers/truth_driver.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-fault-injector: fault markers, GROUND_TRUTH -> MAGRULER_FAULT + FAULT_EVENTS"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);

  return app::runProcess(app, argc, argv, opts, "lcmloc-fault-injector", [&] {
    const auto cfg = simconfig::loadSimSystemConfig(opts.config);
    const auto& sc = cfg.scenario;
    const auto& ch = cfg.channels;
    std::optional<sim::FaultInjector> injector;
    auto start = [&] { injector.emplace(sc.faults, sc.magruler, sim::componentSeed(sc.seed, "faults")); };
    start();

    bus::Bus bus(opts.lcm_url);
    int64_t event_seq = 0;
    drivers::TruthDriver driver(
        bus, cfg, "lcmloc-fault-injector",
        [&](const std::string&, const lcmloc::ground_truth_t& m) {
          auto f = injector->sample(drivers::toCore(m));
          if (!f) return;
          const int64_t measurement_seq = driver.nextSeq();
          bus.publish(ch.magruler_fault, drivers::toLcm(f->reading, measurement_seq));
          lcmloc::fault_event_t ev;
          ev.utime = f->reading.utime;
          ev.seq = event_seq++;
          ev.kind = f->fault.kind;
          ev.channel = ch.magruler_fault;
          ev.measurement_seq = measurement_seq;
          ev.x = f->truth.x;
          ev.y = f->truth.y;
          ev.lateral_offset = f->reading.lateral_offset;
          bus.publish(ch.fault_events, ev);
          spdlog::info("injected {} at {:.2f} m travelled ({:.3f}, {:.3f}): d_m = {:.3f} m on {} seq {}",
                       ev.kind, f->truth.distance, ev.x, ev.y, ev.lateral_offset, ev.channel, measurement_seq);
        },
        start);
    spdlog::info("{} fault(s) configured, publishing on {} and {}", sc.faults.size(), ch.magruler_fault,
                 ch.fault_events);
    return driver.run([&] { return fmt::format("{} faults injected", driver.published()); });
  });
}
