#pragma once
// lcmloc-ctl status and lcmloc-ctl proc: the processes of a running system from the bus, from any
// host. `status` listens to HEARTBEAT for a while and prints one line per process (the table of
// app::ProcessTable: host, pid, state, restarts, CPU %, RSS, message rates, heartbeat age);
// `proc stop|start|restart NAME` sends a process_command_t to the launchers and waits until a
// launcher's heartbeat shows the change.
#include <string>

#include <CLI/CLI.hpp>

#include "lcmloc/app/config.hpp"

namespace lcmloc::ctl {

/// Listens for `seconds` (at least two heartbeat periods, for the rates) and prints the table.
/// Returns app::kExitOk, or app::kExitRuntimeError when no heartbeat came.
int status(const app::SystemConfig& cfg, const std::string& lcm_url, double seconds);

struct ProcCommand {
  std::string command;  ///< stop, start, restart
  std::string process;  ///< the name in the system file
  std::string host;     ///< "" = any launcher that has it
  std::string channel = "LAUNCHER_CONTROL";
};

/// Sends the command and waits (timeout) for a launcher's heartbeat that shows it done: stopped
/// (stop), running with another pid (restart), running (start). Returns app::kExitOk, or
/// kExitNoAnswer when no launcher showed it.
int proc(const app::SystemConfig& cfg, const std::string& lcm_url, const ProcCommand& c, double timeout);

/// The subcommands `status` and `proc` on lcmloc-ctl's command line.
struct ProcessCommands {
  CLI::App* status = nullptr;
  CLI::App* proc = nullptr;
  double listen = 2.5;  ///< status: [s]
  ProcCommand command;  ///< proc
};
void addProcessCommands(CLI::App& app, ProcessCommands& pcs);

}  // namespace lcmloc::ctl
