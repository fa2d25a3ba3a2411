#pragma once
// lcmloc-fusion's process around the FusionDaemon, over any bus::MessageBus (the program runs
// it over LCM, the unit tests over the MemoryBus): the command line beyond the common options, the
// hand-over from a running daemon (--init-from-bus) or a checkpoint (--checkpoint), the check of
// its own POSE echo (another daemon on the bus), the heartbeat, the wall-clock timing
// (FUSION_TIMING), the periodic checkpoint and the stop.
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "checkpoint.hpp"
#include "daemon.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/bus/transport.hpp"

namespace lcmloc::fusion {

struct RunnerOptions {
  std::string filter;             ///< overrides fusion.filter.type ("" = no)
  std::string checkpoint;         ///< checkpoint file ("" = none)
  double init_from_bus = 0.0;     ///< [s, wall] to wait for the running daemon's POSE (0 = off)
  double checkpoint_period = 1.0; ///< [s, wall] between checkpoint writes
};
void addRunnerOptions(CLI::App& app, RunnerOptions& opts);

class DaemonRunner {
 public:
  /// Loads the configuration (with --filter), reads the checkpoint and checks that it can be
  /// written. Throws app::ConfigError for a bad configuration or an unwritable checkpoint,
  /// std::runtime_error for a corrupt one.
  DaemonRunner(const std::string& config_path, RunnerOptions opts);
  /// As above with a configuration already loaded.
  DaemonRunner(app::SystemConfig cfg, RunnerOptions opts);
  ~DaemonRunner();
  DaemonRunner(const DaemonRunner&) = delete;
  DaemonRunner& operator=(const DaemonRunner&) = delete;

  /// Starts the daemon on bus. With --init-from-bus it first waits (up to that long, handling the
  /// bus) for the running daemon's last POSE, until that one reports stopped; else, or when none
  /// came, starts from the checkpoint if there is one, else from the configuration.
  void start(bus::MessageBus& bus);
  /// One turn of the process loop: the heartbeat, bus.handle(timeout_ms), the checkpoint when due.
  void step(int timeout_ms);
  /// The stop: what already arrived is processed (for at most a second), the daemon shuts down
  /// (its final status), the checkpoint is written. Returns the exit code (1 when the checkpoint
  /// could not be written).
  int finish();

  FusionDaemon& daemon() { return *daemon_; }
  const app::SystemConfig& config() const { return cfg_; }

 private:
  /// The last usable POSE of the running daemon on the bus (and its filter), see start().
  std::optional<core::FilterState> lastPoseOnBus(std::string* filter);
  void saveCheckpoint();
  /// FUSION_TIMING (fusion_timing_t) once per wall second.
  void publishTiming();

  app::SystemConfig cfg_;  ///< (the daemon keeps a reference to it)
  RunnerOptions opts_;
  std::optional<Checkpoint> saved_;
  bus::MessageBus* bus_ = nullptr;
  std::unique_ptr<FusionDaemon> daemon_;
  std::unique_ptr<app::Heartbeat> hb_;
  /// A failing write is logged when it starts failing and when it works again (not every period).
  bool checkpoint_failing_ = false, checkpoint_written_ = false;
  std::chrono::steady_clock::time_point last_checkpoint_, last_timing_;
  DaemonTiming timing_;
  int64_t timing_seq_ = 0;
};

}  // namespace lcmloc::fusion
