#pragma once
// config/system.yaml: the processes the launcher starts.
#include <string>
#include <vector>

#include "lcmloc/app/heartbeat.hpp"

namespace lcmloc::launcher {

struct ProcessSpec {
  std::string name;
  std::string executable;          ///< bare name: looked up next to lcmloc-launcher, then in PATH
  std::vector<std::string> args;
  bool until_exit = false;         ///< the run is over when this one exits 0 (the simulator)
  /// Times it is started again after it ended unexpectedly (crashed, or exited while the run
  /// goes on), restart_delay apart; 0: the run fails and the others are stopped. A process that
  /// fails during start-up is not restarted.
  int restart = 0;
  /// false: when it ends for good (after its restarts) or fails during start-up, this is
  /// reported (an error, repeated every kNonCriticalReminder) and the others keep running; the
  /// launcher still exits non-zero at the end. true: the run stops, as before.
  bool critical = true;
};

struct LaunchConfig {
  std::string file;
  std::string scenario;            ///< resolved path of the scenario YAML given to every child
  double drain_time = 1.0;         ///< [s] after an until_exit process ended, before stopping the rest
  double stop_timeout = 5.0;       ///< [s] per process after SIGTERM, then SIGKILL
  double ready_timeout = 5.0;      ///< [s] to wait for a child's first heartbeat
  double restart_delay = 1.0;      ///< [s] from an unexpected end to the restart (ProcessSpec::restart)
  /// [s] the backoff's cap: each restart after a run shorter than this waits twice as long as the
  /// one before (restart_delay, 2x, 4x ... up to this); a run at least this long starts it over.
  double restart_delay_max = 8.0;
  /// [s] between two status tables on the launcher's output (process, host, pid, state, restarts,
  /// CPU, memory, message rates, heartbeat age); 0 = none.
  double status_period = 10.0;
  /// process_command_t (stop, start, restart a process by name: lcmloc-ctl proc) is heard here.
  std::string control_channel = "LAUNCHER_CONTROL";
  /// Directory for the children's run-time files ("{run_dir}" in their args: the daemon's
  /// checkpoint): "" = a new one under the temporary directory for each run, removed at its end.
  std::string run_dir;
  /// [s] a child whose HEARTBEAT (one per second) has been missing this long is hung: stopped
  /// (SIGCONT + SIGTERM, SIGKILL after stop_timeout) and treated as crashed. 0 = off; else at
  /// least kMinHeartbeatTimeout. Watched from the child's first heartbeat on.
  double heartbeat_timeout = 3.0;
  /// [bytes] recv_buf_size added to a udpm:// URL that has none, for the children and the
  /// launcher (0 = the URL as given).
  int recv_buf_size = 4194304;
  std::vector<ProcessSpec> processes;
};

/// Heartbeats come once per app::Heartbeat::kPeriodSeconds (1 s): a shorter timeout than two
/// periods would take a late or lost heartbeat for a hung process.
inline constexpr double kMinHeartbeatTimeout = 2.0 * app::Heartbeat::kPeriodSeconds;

/// Reads a system file; relative scenario paths are relative to the file. Throws ConfigError.
LaunchConfig loadLaunchConfig(const std::string& path);

}  // namespace lcmloc::launcher
