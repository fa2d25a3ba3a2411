// lcmloc-magruler: the magnetic ruler (13 AMR sensors + peak mapping).
// GROUND_TRUTH -> MagneticRuler -> MAGRULER (a detection as the ruler passes a marker).
#include <spdlog/spdlog.h>

#include <optional>

#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/drivers/truth_driver.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-magruler: simulated magnetic ruler, GROUND_TRUTH -> MAGRULER"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);

  return app::runProcess(app, argc, argv, opts, "lcmloc-magruler", [&] {
    const auto cfg = simconfig::loadSimSystemConfig(opts.config);
    const auto& sc = cfg.scenario;
    const std::string out = cfg.channels.magruler.empty() ? "MAGRULER" : cfg.channels.magruler.front();
    const auto map = sim::makeMarkerMap(sim::Path(sc.path), sc.markers);
    std::optional<sim::MagneticRuler> ruler;
    auto start = [&] { ruler.emplace(sc.magruler, map, sim::componentSeed(sc.seed, "magruler")); };
    start();

    bus::Bus bus(opts.lcm_url);
    int64_t detections = 0;
    drivers::TruthDriver driver(
        bus, cfg, "lcmloc-magruler",
        [&](const std::string&, const lcmloc::ground_truth_t& m) {
          if (auto r = ruler->sample(drivers::toCore(m))) {
            if (r->detected) {
              ++detections;
              spdlog::debug("marker detected at utime {}: d_m = {:.4f} m", r->utime, r->lateral_offset);
            }
            bus.publish(out, drivers::toLcm(*r, driver.nextSeq()));
          }
        },
        start, [&] { return app::Heartbeat::Counters{{"detections", detections}}; });
    spdlog::info("{} -> {}: {} markers in the map, {} sensors", cfg.channels.ground_truth, out, map.size(),
                 sc.magruler.num_sensors);
    return driver.run([&] { return fmt::format("{} readings out ({} detections)", driver.published(), detections); });
  });
}
