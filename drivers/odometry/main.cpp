// lcmloc-odometry: drive and steering encoders. GROUND_TRUTH -> OdometrySensor -> ODOMETRY.
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
  CLI::App app{"lcmloc-odometry: simulated encoders, GROUND_TRUTH -> ODOMETRY"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);

  return app::runProcess(app, argc, argv, opts, "lcmloc-odometry", [&] {
    const auto cfg = simconfig::loadSimSystemConfig(opts.config);
    const auto& sc = cfg.scenario;
    std::optional<sim::OdometrySensor> sensor;
    auto start = [&] { sensor.emplace(sc.odometry, sc.vehicle.wheelbase, sim::componentSeed(sc.seed, "odometry")); };
    start();

    bus::Bus bus(opts.lcm_url);
    drivers::TruthDriver driver(
        bus, cfg, "lcmloc-odometry",
        [&](const std::string&, const lcmloc::ground_truth_t& m) {
          if (auto s = sensor->sample(drivers::toCore(m)))
            bus.publish(cfg.channels.odometry, drivers::toLcm(*s, driver.nextSeq()));
        },
        start);
    spdlog::info("{} -> {} at {} Hz, scale error {}, steering bias {} rad", cfg.channels.ground_truth,
                 cfg.channels.odometry, sc.odometry.rate_hz, sc.odometry.scale_error, sc.odometry.steering_bias);
    return driver.run([&] { return fmt::format("{} odometry out", driver.published()); });
  });
}
