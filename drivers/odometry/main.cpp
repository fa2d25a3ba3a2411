// lcmloc-odometry: drive and steering encoders. GROUND_TRUTH -> OdometrySensor -> ODOMETRY.
#include <spdlog/spdlog.h>

#include "lcmloc/common/config.hpp"
#include "lcmloc/common/convert.hpp"
#include "lcmloc/common/process.hpp"
#include "lcmloc/models/world.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-odometry: simulated encoders, GROUND_TRUTH -> ODOMETRY"};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);

  return common::runProcess(app, argc, argv, opts, "lcmloc-odometry", [&] {
    const auto cfg = common::loadSystemConfig(opts.config);
    const auto& sc = cfg.scenario;
    models::OdometrySensor sensor(sc.odometry, sc.vehicle.wheelbase,
                                  models::componentSeed(sc.seed, "odometry"));

    common::Bus bus(opts.lcm_url);
    common::SeqTracker gaps;
    int64_t received = 0, seq = 0;
    bus.subscribe<lcmloc::ground_truth_t>(
        cfg.channels.ground_truth, [&](const std::string& ch, const lcmloc::ground_truth_t& m, int64_t) {
          ++received;
          if (const auto gap = gaps.observe(ch, m.seq))
            spdlog::warn("{}", gap.describe(ch));
          if (auto s = sensor.sample(common::toCore(m)))
            bus.publish(cfg.channels.odometry, common::toLcm(*s, seq++));
        });
    common::Heartbeat hb(bus, cfg.channels.heartbeat, "lcmloc-odometry", [&] {
      return common::Heartbeat::Counters{
          {"received", received}, {"published", seq}, {"gaps", gaps.gaps()}, {"decode_errors", bus.decodeErrors()}};
    });
    spdlog::info("{} -> {} at {} Hz, scale error {}, steering bias {} rad", cfg.channels.ground_truth,
                 cfg.channels.odometry, sc.odometry.rate_hz, sc.odometry.scale_error, sc.odometry.steering_bias);
    while (!common::stopRequested()) {
      hb.tick();
      bus.handle(100);
    }
    spdlog::info("stopping: {} ground-truth samples in, {} odometry out, {} gaps", received, seq, gaps.gaps());
    hb.publish("stopping");
    return common::kExitOk;
  });
}
