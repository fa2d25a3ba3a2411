#pragma once
// config/system.yaml: the processes the launcher starts.
#include <string>
#include <vector>

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
};

struct LaunchConfig {
  std::string file;
  std::string scenario;            ///< resolved path of the scenario YAML given to every child
  double drain_time = 1.0;         ///< [s] after an until_exit process ended, before stopping the rest
  double stop_timeout = 5.0;       ///< [s] per process after SIGTERM, then SIGKILL
  double ready_timeout = 5.0;      ///< [s] to wait for a child's first heartbeat
  double restart_delay = 1.0;      ///< [s] from an unexpected end to the restart (ProcessSpec::restart)
  std::vector<ProcessSpec> processes;
};

/// Reads a system file; relative scenario paths are relative to the file. Throws ConfigError.
LaunchConfig loadLaunchConfig(const std::string& path);

}  // namespace lcmloc::launcher
