// lcmloc-vision: simulated electro-optical detection system (seeds/004 §III).
// GROUND_TRUTH -> VisionSensor (bearings to the landmark map, noise, resolution; lib/sim)
// -> VISION (landmark_bearings_t).
#include <spdlog/spdlog.h>

#include <optional>

#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/drivers/truth_driver.hpp"
#include "lcmloc/sim/vision_sensor.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-vision: simulated bearings to known landmarks, GROUND_TRUTH -> VISION"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  double rate = 0.0;
  app.add_option("--rate", rate, "override vision.rate_hz [Hz]")->check(CLI::Range(simconfig::kVisionRateHz.lo, simconfig::kVisionRateHz.hi));

  return app::runProcess(app, argc, argv, opts, "lcmloc-vision", [&] {
    auto cfg = simconfig::loadSimSystemConfig(opts.config);
    auto& sc = cfg.scenario;
    if (rate > 0) sc.vision.rate_hz = rate;
    if (sc.landmarks.size() < 3)
      throw app::ConfigError(cfg.file, "landmarks",
                                fmt::format("{} landmark(s): the three-landmark fix needs at least 3 (list of {{id, x, y}})",
                                            sc.landmarks.size()));
    const uint64_t seed = sc.vision.seed ? sc.vision.seed : sim::componentSeed(sc.seed, "vision");
    std::optional<sim::VisionSensor> sensor;
    auto start = [&] { sensor.emplace(sc.vision, sc.landmarks, seed); };
    start();

    bus::Bus bus(opts.lcm_url);
    int64_t empty = 0;
    // Ground truth with a non-finite pose never gets here: TruthDriver refuses it (and counts it
    // as bad_truth) for every driver.
    drivers::TruthDriver driver(
        bus, cfg, "lcmloc-vision",
        [&](const std::string&, const lcmloc::ground_truth_t& m) {
          if (auto s = sensor->sample(drivers::toCore(m))) {
            if (s->ids.empty() && empty++ == 0)
              spdlog::info("no landmark within {} m at utime {}", sc.vision.max_range, s->utime);
            bus.publish(cfg.channels.vision, drivers::toLcm(*s, driver.nextSeq()));
          }
        },
        start, [&] { return app::Heartbeat::Counters{{"empty", empty}}; });
    spdlog::info("{} -> {} at {} Hz, {} landmark(s), noise {:.1f}\" (1 sigma), resolution {:.1f}\", max range {} m",
                 cfg.channels.ground_truth, cfg.channels.vision, sc.vision.rate_hz, sc.landmarks.size(),
                 sc.vision.bearing_std / sim::kArcSec, sc.vision.resolution / sim::kArcSec,
                 sc.vision.max_range);
    return driver.run([&] {
      return fmt::format("{} observations out ({} with no landmark)", driver.published(), empty);
    });
  });
}
