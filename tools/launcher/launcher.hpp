#pragma once
// lcmloc-launcher's work: starts the processes of a system file as children (in list order, each
// once its heartbeat shows it running), watches them (their exit, and their HEARTBEAT: one silent
// for heartbeat_timeout is hung, and stopped), starts a child that ended unexpectedly again when
// its `restart` allows, and stops them in reverse order when the until_exit process (the
// simulator) has finished, when a critical child fails for good, or on a stop request
// (app::stopRequested). A non-critical child that fails for good is reported and the others
// keep running.
#include <string>

#include "launch_config.hpp"

namespace lcmloc::launcher {

/// Runs the system cfg, every child with --config scenario --lcm-url url. Returns
/// app::kExitOk, or kExitRuntimeError if any child failed (in its last run).
int run(LaunchConfig cfg, const std::string& scenario, const std::string& url);

/// Loads the system file, takes config (the scenario for every child; "" = the system file's
/// `scenario`, else the default config) and lcm_url (given the system file's recv_buf_size when a
/// udpm:// URL has none), says what it starts and runs it (run()). Throws ConfigError.
int launch(const std::string& system_file, const std::string& config, const std::string& lcm_url);

}  // namespace lcmloc::launcher
