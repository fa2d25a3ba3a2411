// lcmloc-imu: simulated 3-axis accelerometer, gyroscope and magnetometer.
// GROUND_TRUTH -> ImuSensor (noise, constant + drifting biases, declination, disturbance,
// saturation; lib/sim) -> IMU.
#include <spdlog/spdlog.h>

#include <optional>

#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/drivers/truth_driver.hpp"
#include "lcmloc/sim/gnss_sensors.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-imu: simulated IMU (accel, gyro, mag), GROUND_TRUTH -> IMU"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  double rate = 0.0;
  app.add_option("--rate", rate, "override imu.rate_hz [Hz]")->check(CLI::Range(simconfig::kImuRateHz.lo, simconfig::kImuRateHz.hi));

  return app::runProcess(app, argc, argv, opts, "lcmloc-imu", [&] {
    auto cfg = simconfig::loadSimSystemConfig(opts.config);
    auto& sc = cfg.scenario;
    if (rate > 0) {
      sc.imu.rate_hz = rate;
      simconfig::checkSampledRate(rate, sc, "--rate", "imu.rate_hz");
    }
    std::optional<sim::ImuSensor> sensor;
    auto start = [&] { sensor.emplace(sc.imu, sc.vehicle.wheelbase, sim::componentSeed(sc.seed, "imu")); };
    start();

    bus::Bus bus(opts.lcm_url);
    int64_t saturated = 0;
    const double range = sc.imu.accel_range;
    drivers::TruthDriver driver(
        bus, cfg, "lcmloc-imu",
        [&](const std::string&, const lcmloc::ground_truth_t& m) {
          if (auto s = sensor->sample(drivers::toCore(m))) {
            if (range > 0 && s->accel.cwiseAbs().maxCoeff() >= range && saturated++ < 5)
              spdlog::warn("accelerometer saturated at utime {} (range {} m/s^2)", s->utime, range);
            bus.publish(cfg.channels.imu, drivers::toLcm(*s, driver.nextSeq()));
          }
        },
        start, [&] { return app::Heartbeat::Counters{{"saturated", saturated}}; });
    spdlog::info("{} -> {} at {} Hz, declination {} rad, accel range {} m/s^2", cfg.channels.ground_truth,
                 cfg.channels.imu, sc.imu.rate_hz, sc.imu.declination, range);
    return driver.run([&] { return fmt::format("{} IMU samples out ({} saturated)", driver.published(), saturated); });
  });
}
