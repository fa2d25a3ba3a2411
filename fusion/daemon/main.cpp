// lcmloc-fusion: the fusion daemon (see daemon.hpp).
#include <chrono>
#include <memory>
#include <optional>

#include <spdlog/spdlog.h>

#include "daemon.hpp"
#include "checkpoint.hpp"
#include "lcmloc/bus/convert.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/pose_t.hpp"

using namespace lcmloc;

namespace {

/// Process-level hand-over: listens for the running daemon's POSE until it reports "stopped" on
/// the status channel or the timeout passes; returns its last POSE. (The bus cannot drop a
/// subscription: the handlers keep their state on the heap and ignore what comes afterwards.)
std::optional<core::FilterState> lastPoseOnBus(common::Bus& bus, const common::SystemConfig& cfg,
                                               common::Heartbeat& hb, double timeout_s, std::string* filter) {
  struct Watch {
    std::optional<core::FilterState> last;
    std::string filter;
    bool waiting = true, stopped = false, warned = false;
  };
  auto w = std::make_shared<Watch>();
  const std::string pose_channel = cfg.channels.pose;
  bus.subscribe<lcmloc::pose_t>(pose_channel, [w, pose_channel](const std::string&, const lcmloc::pose_t& m, int64_t) {
    if (!w->waiting || m.dim < 3 || static_cast<int>(m.state.size()) < 3) return;
    core::FilterState s = common::toCore(m);
    if (const std::string why = core::unusableState(s); !why.empty()) {
      if (!w->warned) spdlog::warn("a {} on the bus no filter can start from, not taken: {}", pose_channel, why);
      w->warned = true;
      return;
    }
    w->last = std::move(s);
    w->filter = m.filter;
  });
  bus.subscribe<lcmloc::fusion_status_t>(
      cfg.channels.status, [w](const std::string&, const lcmloc::fusion_status_t& m, int64_t) {
        if (w->waiting && m.event == "stopped") w->stopped = true;
      });
  spdlog::info("waiting up to {:.1f} s for the running daemon's last {} (until it reports stopped on {})", timeout_s,
               cfg.channels.pose, cfg.channels.status);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!common::stopRequested() && !w->stopped && std::chrono::steady_clock::now() < deadline) {
    hb.tick();
    bus.handle(50);
  }
  bus.drain();  // (a flood is taken by the daemon's loop then)
  w->waiting = false;
  if (w->last && !w->stopped)
    spdlog::warn("the daemon that published {} did not report stopped within {:.1f} s: it may still be running",
                 cfg.channels.pose, timeout_s);
  *filter = w->filter;
  return w->last;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-fusion: fusion daemon, ODOMETRY + MAGRULER* + IMU + GPS + LANDMARKS + BEACONS + VISION + "
               "FUSION_CONTROL -> POSE (POSE_<TYPE> for shadows), GATE, FUSION_STATUS"};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);
  std::string filter, checkpoint;
  double init_from_bus = 0.0, checkpoint_period = 1.0;
  app.add_option("--filter", filter, "override fusion.filter.type (" + lcmloc::core::filterTypeList() + ")");
  app.add_option("--init-from-bus", init_from_bus,
                 "hand-over from a running daemon: wait up to SECONDS for its POSE, until it reports stopped, "
                 "and start from its last POSE (inputs are queued meanwhile); 0 = off")
      ->check(lcmloc::common::wallSeconds());
  app.add_option("--checkpoint", checkpoint,
                 "checkpoint FILE: start from it if it exists (after --init-from-bus found nothing), write the "
                 "active filter's state to it periodically and at exit");
  app.add_option("--checkpoint-period", checkpoint_period, "[s, wall] between checkpoint writes")
      ->check(lcmloc::common::positive())
      ->check(lcmloc::common::wallSeconds());

  return common::runProcess(app, argc, argv, opts, "lcmloc-fusion", [&] {
    auto cfg = common::loadSystemConfig(opts.config);
    if (!filter.empty()) {
      YAML::Node n;
      n["type"] = filter;
      cfg.fusion.filter = common::parseFilterConfig(n, cfg.fusion.filter, "--filter", "fusion.filter");
    }
    std::optional<fusion::Checkpoint> saved;
    if (!checkpoint.empty()) {
      saved = fusion::readCheckpoint(checkpoint);  // a corrupt file is an error now
      if (const std::string why = fusion::checkpointUnwritable(checkpoint); !why.empty())
        throw common::ConfigError(checkpoint, "--checkpoint", why);
    }
    common::Bus bus(opts.lcm_url);
    const bool hold = init_from_bus > 0 || !checkpoint.empty();
    fusion::FusionDaemon daemon(cfg, bus, fusion::FusionDaemon::Options{hold, true});
    common::Heartbeat hb(bus, cfg.channels.heartbeat, "lcmloc-fusion", [&] { return daemon.counters(); });
    if (hold) {
      std::optional<core::FilterState> init;
      std::string source, from_filter;
      bool from_bus = false;
      if (init_from_bus > 0) {
        init = lastPoseOnBus(bus, cfg, hb, init_from_bus, &from_filter);
        if (init) source = "the last " + cfg.channels.pose + " on the bus (filter " + from_filter + ")";
        from_bus = init.has_value();
      }
      if (!init && saved) {
        init = saved->state;
        source = "checkpoint " + checkpoint + " (filter " + saved->filter + ")";
      }
      if (!init) source = init_from_bus > 0 ? "no POSE on the bus and no checkpoint" : "no checkpoint yet";
      daemon.release(init, source, from_bus);  // the daemon handed over from saw what was queued
      if (!init && init_from_bus > 0)
        daemon.warn("no_handover",
                    fmt::format("no {} on the bus within {:.1f} s{}: the filters start from the configured initial "
                                "state, which is wrong if the vehicle is elsewhere (a daemon started again after a "
                                "crash finds no POSE: run it with --checkpoint). Give the pose with lcmloc-ctl "
                                "set-pose X Y THETA",
                                cfg.channels.pose, init_from_bus, checkpoint.empty() ? "" : " and no checkpoint"));
    }
    // Its own POSE comes back (loopback); one it did not publish is another daemon's.
    bus.subscribe<lcmloc::pose_t>(cfg.channels.pose, [&daemon](const std::string&, const lcmloc::pose_t& m, int64_t) {
      daemon.checkEcho(m);
    });
    // A failing write is logged when it starts failing and when it works again (not every period).
    bool checkpoint_failing = false, checkpoint_written = false;
    auto saveCheckpoint = [&] {
      if (checkpoint.empty() || daemon.processed() == 0) return;
      try {
        fusion::writeCheckpoint(checkpoint, daemon.activeState(), daemon.activeFilter());
        if (checkpoint_failing) spdlog::info("checkpoint {} written again", checkpoint);
        checkpoint_failing = false;
        checkpoint_written = true;
      } catch (const std::exception& e) {
        if (!checkpoint_failing) spdlog::error("{} (retried every {} s)", e.what(), checkpoint_period);
        checkpoint_failing = true;
      }
    };
    auto last_checkpoint = std::chrono::steady_clock::now();
    while (!common::stopRequested()) {
      hb.tick();
      bus.handle(100);
      if (!checkpoint.empty() &&
          std::chrono::steady_clock::now() - last_checkpoint >= std::chrono::duration<double>(checkpoint_period)) {
        saveCheckpoint();
        last_checkpoint = std::chrono::steady_clock::now();
      }
    }
    // What already arrived is processed too, for at most a second: a sender flooding the bus must
    // not keep the daemon from stopping.
    if (!bus.drain()) spdlog::warn("inputs still arriving after 1 s of stopping: the rest are not processed");
    daemon.shutdown();
    saveCheckpoint();
    hb.publish("stopping");
    if (checkpoint.empty()) return common::kExitOk;
    if (checkpoint_failing) {
      spdlog::error("the checkpoint {} could not be written at exit", checkpoint);
      return common::kExitRuntimeError;
    }
    if (checkpoint_written)
      spdlog::info("checkpoint written to {}", checkpoint);
    else
      spdlog::info("no input processed: checkpoint {} left as it was", checkpoint);
    return common::kExitOk;
  });
}
