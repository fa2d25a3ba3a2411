// lcmloc-logger: records channels to standard LCM log files (lcm-logplayer plays them). The LCM
// thread only enqueues; a writer thread writes. Rotation by size and time, SIGHUP starts a new
// file, fsync every flush period, clean close on SIGINT/SIGTERM, a clear error and exit 1 when
// the disk fills up. The behaviour is logger::Recorder's (recorder.hpp).
#include <signal.h>

#include <atomic>
#include <csignal>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "recorder.hpp"

using namespace lcmloc;

namespace {
std::atomic<bool> g_hup{false};
extern "C" void onHup(int) { g_hup.store(true); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-logger: records LCM channels to log files that lcm-logplayer plays.\n"
               "SIGINT/SIGTERM: write what is queued, close and exit; SIGHUP: start a new file (one that cannot be "
               "opened is reported, and recording goes on into the current file; tried again at the next SIGHUP)."};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  logger::LoggerFlags flags;
  logger::addLoggerFlags(app, flags);

  return app::runProcess(app, argc, argv, opts, "lcmloc-logger", [&] {
    const auto cfg = app::loadSystemConfig(opts.config);
    struct sigaction sa {};
    sa.sa_handler = onHup;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGHUP, &sa, nullptr);  // no SA_RESTART: the LCM wait returns at once
    std::signal(SIGXFSZ, SIG_IGN);     // a file size limit becomes EFBIG, handled like a full disk
    const logger::RecorderOptions ro = logger::recorderOptions(cfg, flags);
    const std::string url = bus::withReceiveBuffer(opts.lcm_url, cfg.logger.recv_buf_size);

    bus::Bus bus(url);
    logger::Recorder recorder(ro, bus);
    // (after the subscription: the bus opens its receive socket then)
    logger::sizeReceiveBuffer(url, cfg.logger.recv_buf_size);
    while (!app::stopRequested()) {
      if (g_hup.exchange(false)) recorder.requestRotate();
      if (!recorder.step(100)) break;  // a write error
    }
    return recorder.finish();
  });
}
