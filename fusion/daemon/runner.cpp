#include "runner.hpp"

#include <spdlog/spdlog.h>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/convert.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::fusion {

void addRunnerOptions(CLI::App& app, RunnerOptions& o) {
  app.add_option("--filter", o.filter, "override fusion.filter.type (" + lcmloc::core::filterTypeList() + ")");
  app.add_option("--init-from-bus", o.init_from_bus,
                 "hand-over from a running daemon: wait up to SECONDS for its POSE, until it reports stopped, "
                 "and start from its last POSE (inputs are queued meanwhile); 0 = off")
      ->check(app::wallSeconds());
  app.add_option("--checkpoint", o.checkpoint,
                 "checkpoint FILE: start from it if it exists (after --init-from-bus found nothing), write the "
                 "active filter's state to it periodically and at exit");
  app.add_option("--checkpoint-period", o.checkpoint_period, "[s, wall] between checkpoint writes")
      ->check(app::positive())
      ->check(app::wallSeconds());
}

DaemonRunner::DaemonRunner(const std::string& config_path, RunnerOptions opts)
    : DaemonRunner(app::loadSystemConfig(config_path), std::move(opts)) {}

DaemonRunner::DaemonRunner(app::SystemConfig cfg, RunnerOptions opts) : cfg_(std::move(cfg)), opts_(std::move(opts)) {
  if (!opts_.filter.empty()) {
    YAML::Node n;
    n["type"] = opts_.filter;
    cfg_.fusion.filter = app::parseFilterConfig(n, cfg_.fusion.filter, "--filter", "fusion.filter");
  }
  if (!opts_.checkpoint.empty()) {
    saved_ = readCheckpoint(opts_.checkpoint);  // a corrupt file is an error now
    if (const std::string why = checkpointUnwritable(opts_.checkpoint); !why.empty())
      throw app::ConfigError(opts_.checkpoint, "--checkpoint", why);
  }
}

DaemonRunner::~DaemonRunner() = default;

std::optional<core::FilterState> DaemonRunner::lastPoseOnBus(std::string* filter) {
  // Listens for the running daemon's POSE until it reports "stopped" on the status channel or the
  // timeout passes. (The bus cannot drop a subscription: the handlers keep their state on the
  // heap and ignore what comes afterwards.)
  struct Watch {
    std::optional<core::FilterState> last;
    std::string filter;
    bool waiting = true, stopped = false, warned = false;
  };
  auto w = std::make_shared<Watch>();
  const std::string pose_channel = cfg_.channels.pose;
  bus_->subscribe<lcmloc::pose_t>(pose_channel, [w, pose_channel](const std::string&, const lcmloc::pose_t& m, int64_t) {
    if (!w->waiting || m.dim < 3 || static_cast<int>(m.state.size()) < 3) return;
    core::FilterState s = bus::toCore(m);
    if (const std::string why = core::unusableState(s); !why.empty()) {
      if (!w->warned) spdlog::warn("a {} on the bus no filter can start from, not taken: {}", pose_channel, why);
      w->warned = true;
      return;
    }
    w->last = std::move(s);
    w->filter = m.filter;
  });
  bus_->subscribe<lcmloc::fusion_status_t>(
      cfg_.channels.status, [w](const std::string&, const lcmloc::fusion_status_t& m, int64_t) {
        if (w->waiting && m.event == "stopped") w->stopped = true;
      });
  const double timeout_s = opts_.init_from_bus;
  spdlog::info("waiting up to {:.1f} s for the running daemon's last {} (until it reports stopped on {})", timeout_s,
               cfg_.channels.pose, cfg_.channels.status);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!app::stopRequested() && !w->stopped && std::chrono::steady_clock::now() < deadline) {
    hb_->tick();
    bus_->handle(50);
  }
  bus_->drain();  // (a flood is taken by the daemon's loop then)
  w->waiting = false;
  if (w->last && !w->stopped)
    spdlog::warn("the daemon that published {} did not report stopped within {:.1f} s: it may still be running",
                 cfg_.channels.pose, timeout_s);
  *filter = w->filter;
  return w->last;
}

void DaemonRunner::start(bus::MessageBus& bus) {
  bus_ = &bus;
  // A checkpoint that does not exist yet (the first start) changes nothing: the daemon starts
  // exactly as without --checkpoint, so its outputs equal those of a replay.
  const bool hold = opts_.init_from_bus > 0 || saved_.has_value();
  if (!opts_.checkpoint.empty() && !saved_)
    spdlog::info("no checkpoint {} yet: starting from the configured initial state", opts_.checkpoint);
  daemon_ = std::make_unique<FusionDaemon>(cfg_, bus, FusionDaemon::Options{hold, true, true, &timing_});
  hb_ = std::make_unique<app::Heartbeat>(bus, cfg_.channels.heartbeat, "lcmloc-fusion",
                                            [this] { return daemon_->counters(); });
  if (hold) {
    std::optional<core::FilterState> init;
    std::string source, from_filter;
    bool from_bus = false;
    if (opts_.init_from_bus > 0) {
      init = lastPoseOnBus(&from_filter);
      if (init) source = "the last " + cfg_.channels.pose + " on the bus (filter " + from_filter + ")";
      from_bus = init.has_value();
    }
    if (!init && saved_) {
      init = saved_->state;
      source = "checkpoint " + opts_.checkpoint + " (filter " + saved_->filter + ")";
    }
    if (!init) source = "no POSE on the bus and no checkpoint";
    daemon_->release(init, source, from_bus);  // the daemon handed over from saw what was queued
    if (!init && opts_.init_from_bus > 0)
      daemon_->warn("no_handover",
                    fmt::format("no {} on the bus within {:.1f} s{}: the filters start from the configured initial "
                                "state, which is wrong if the vehicle is elsewhere (a daemon started again after a "
                                "crash finds no POSE: run it with --checkpoint). Give the pose with lcmloc-ctl "
                                "set-pose X Y THETA",
                                cfg_.channels.pose, opts_.init_from_bus, opts_.checkpoint.empty() ? "" : " and no checkpoint"));
  }
  // Its own POSE comes back (loopback); one it did not publish is another daemon's.
  FusionDaemon* d = daemon_.get();
  bus.subscribe<lcmloc::pose_t>(cfg_.channels.pose,
                                [d](const std::string&, const lcmloc::pose_t& m, int64_t) { d->checkEcho(m); });
  last_checkpoint_ = last_timing_ = std::chrono::steady_clock::now();
}

void DaemonRunner::publishTiming() {
  const auto now = std::chrono::steady_clock::now();
  if (now - last_timing_ < std::chrono::seconds(1)) return;
  last_timing_ = now;
  const auto wall = std::chrono::duration_cast<std::chrono::microseconds>(
      std::chrono::system_clock::now().time_since_epoch());
  lcmloc::fusion_timing_t m = timing_.report(wall.count(), daemon_->lateInputs());
  m.horizon = static_cast<double>(daemon_->horizonUs()) * 1e-6;
  m.released_early = daemon_->releasedEarly();
  m.seq = timing_seq_++;
  bus_->publish(cfg_.channels.timing, m);
}

void DaemonRunner::saveCheckpoint() {
  if (opts_.checkpoint.empty() || daemon_->processed() == 0) return;
  try {
    writeCheckpoint(opts_.checkpoint, daemon_->activeState(), daemon_->activeFilter());
    if (checkpoint_failing_) spdlog::info("checkpoint {} written again", opts_.checkpoint);
    checkpoint_failing_ = false;
    checkpoint_written_ = true;
  } catch (const std::exception& e) {
    if (!checkpoint_failing_) spdlog::error("{} (retried every {} s)", e.what(), opts_.checkpoint_period);
    checkpoint_failing_ = true;
  }
}

void DaemonRunner::step(int timeout_ms) {
  hb_->tick();
  bus_->handle(timeout_ms);
  publishTiming();
  if (!opts_.checkpoint.empty() &&
      std::chrono::steady_clock::now() - last_checkpoint_ >= std::chrono::duration<double>(opts_.checkpoint_period)) {
    saveCheckpoint();
    last_checkpoint_ = std::chrono::steady_clock::now();
  }
}

int DaemonRunner::finish() {
  // What already arrived is processed too, for at most a second: a sender flooding the bus must
  // not keep the daemon from stopping.
  if (!bus_->drain()) spdlog::warn("inputs still arriving after 1 s of stopping: the rest are not processed");
  daemon_->shutdown();
  saveCheckpoint();
  hb_->publish("stopping");
  if (opts_.checkpoint.empty()) return app::kExitOk;
  if (checkpoint_failing_) {
    spdlog::error("the checkpoint {} could not be written at exit", opts_.checkpoint);
    return app::kExitRuntimeError;
  }
  if (checkpoint_written_)
    spdlog::info("checkpoint written to {}", opts_.checkpoint);
  else
    spdlog::info("no input processed: checkpoint {} left as it was", opts_.checkpoint);
  return app::kExitOk;
}

}  // namespace lcmloc::fusion
