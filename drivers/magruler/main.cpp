// lcmloc-magruler: the magnetic ruler (13 AMR sensors + peak mapping).
// GROUND_TRUTH -> MagneticRuler -> MAGRULER (a detection as the ruler passes a marker).
#include <spdlog/spdlog.h>

#include "lcmloc/common/config.hpp"
#include "lcmloc/common/convert.hpp"
#include "lcmloc/common/process.hpp"
#include "lcmloc/models/world.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-magruler: simulated magnetic ruler, GROUND_TRUTH -> MAGRULER"};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);

  return common::runProcess(app, argc, argv, opts, "lcmloc-magruler", [&] {
    const auto cfg = common::loadSystemConfig(opts.config);
    const auto& sc = cfg.scenario;
    const std::string out = cfg.channels.magruler.empty() ? "MAGRULER" : cfg.channels.magruler.front();
    const auto map = models::makeMarkerMap(models::Path(sc.path), sc.markers);
    models::MagneticRuler ruler(sc.magruler, map, models::componentSeed(sc.seed, "magruler"));

    common::Bus bus(opts.lcm_url);
    common::SeqTracker gaps;
    int64_t received = 0, seq = 0, detections = 0;
    bus.subscribe<lcmloc::ground_truth_t>(
        cfg.channels.ground_truth, [&](const std::string& ch, const lcmloc::ground_truth_t& m, int64_t) {
          ++received;
          if (const auto gap = gaps.observe(ch, m.seq))
            spdlog::warn("{}", gap.describe(ch));
          if (auto r = ruler.sample(common::toCore(m))) {
            if (r->detected) {
              ++detections;
              spdlog::debug("marker detected at utime {}: d_m = {:.4f} m", r->utime, r->lateral_offset);
            }
            bus.publish(out, common::toLcm(*r, seq++));
          }
        });
    common::Heartbeat hb(bus, cfg.channels.heartbeat, "lcmloc-magruler", [&] {
      return common::Heartbeat::Counters{{"received", received}, {"published", seq},
                                         {"detections", detections}, {"gaps", gaps.gaps()}};
    });
    spdlog::info("{} -> {}: {} markers in the map, {} sensors", cfg.channels.ground_truth, out, map.size(),
                 sc.magruler.num_sensors);
    while (!common::stopRequested()) {
      hb.tick();
      bus.handle(100);
    }
    spdlog::info("stopping: {} ground-truth samples in, {} readings out ({} detections), {} gaps", received,
                 seq, detections, gaps.gaps());
    hb.publish("stopping");
    return common::kExitOk;
  });
}
