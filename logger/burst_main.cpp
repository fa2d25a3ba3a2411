// lcmloc-burst: publishes magruler_t messages of a chosen encoded size as fast as possible
// (seq 0, 1, ...), for benchmarking loggers (tools/bench_logger.sh).
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/magruler_t.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-burst: publishes a burst of magruler_t messages as fast as possible"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  int64_t count = 1000;
  int size = 100;
  std::string channel = "BURST";
  app.add_option("--count,-n", count, "messages to publish")->check(lcmloc::app::positive());
  app.add_option("--size,-s", size, "encoded message size [bytes] (at least 45)")->check(CLI::Range(45, 60000));
  app.add_option("--channel,-c", channel, "channel");
  app.footer("--config is only checked (a bad file exits 2, as everywhere): a burst needs no settings.");
  return app::runProcess(app, argc, argv, opts, "lcmloc-burst", [&] {
    app::loadSystemConfig(opts.config);
    bus::Bus bus(opts.lcm_url);
    lcmloc::magruler_t m;
    m.num_sensors = (size - 45) / 8;  // 45 bytes of fixed fields (fingerprint included) + 8 per reading
    m.readings.assign(static_cast<std::size_t>(m.num_sensors), 0.5);
    m.detected = false;
    m.lateral_offset = 0;
    m.quality = 0;
    const int bytes = m.getEncodedSize();
    const auto t0 = std::chrono::steady_clock::now();
    int64_t failed = 0, sent = 0;
    for (; sent < count && !app::stopRequested(); ++sent) {
      m.utime = bus::wallMicros();
      m.seq = sent;
      if (!bus.publish(channel, m)) ++failed;
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    spdlog::info("published {} messages of {} bytes on {} in {:.3f} s ({:.0f} msg/s), {} failed{}", sent, bytes,
                 channel, s, static_cast<double>(sent) / s, failed,
                 sent < count ? fmt::format(" (stopped: {} of {} not sent)", count - sent, count) : "");
    return failed ? app::kExitRuntimeError : app::kExitOk;
  });
}
