// lcmloc-ctl status and proc (see processes.hpp).
#include "lcmloc/ctl/processes.hpp"

#include <unistd.h>

#include <chrono>
#include <iostream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/process_table.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/ctl/control.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/process_command_t.hpp"

namespace lcmloc::ctl {

using Clock = std::chrono::steady_clock;

int status(const app::SystemConfig& cfg, const std::string& lcm_url, double seconds) {
  bus::Bus bus(lcm_url);
  app::ProcessTable table;
  bus.subscribe<lcmloc::heartbeat_t>(cfg.channels.heartbeat,
                                     [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t recv) {
                                       table.observe(m, recv);
                                     });
  const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < deadline && !app::stopRequested()) bus.handle(50);
  if (table.empty()) {
    spdlog::error("no {} on the bus within {:.1f} s: is the system running (and the LCM URL that of the system)?",
                  cfg.channels.heartbeat, seconds);
    return app::kExitRuntimeError;
  }
  std::cout << app::formatProcessTable(table.rows()) << std::flush;
  return app::kExitOk;
}

int proc(const app::SystemConfig& cfg, const std::string& lcm_url, const ProcCommand& c, double timeout) {
  bus::Bus bus(lcm_url);
  app::ProcessTable table;
  bus.subscribe<lcmloc::heartbeat_t>(cfg.channels.heartbeat,
                                     [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t recv) {
                                       if (m.process == "lcmloc-launcher") table.observe(m, recv);
                                     });
  // The process as the launchers show it (host "" = any).
  const auto find = [&]() -> std::optional<app::ProcessRow> {
    for (const auto& r : table.rows())
      if (r.name == c.process && (c.host.empty() || r.host == c.host) && r.restarts >= 0) return r;
    return std::nullopt;
  };
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
  while (!find() && Clock::now() < deadline && !app::stopRequested()) bus.handle(50);
  const auto before = find();
  if (!before) {
    std::cout << fmt::format("no launcher on the bus shows a process '{}'{} within {:.1f} s\n", c.process,
                             c.host.empty() ? "" : " on host " + c.host, timeout);
    return kExitNoAnswer;
  }
  lcmloc::process_command_t m{};
  m.utime = bus::wallMicros();
  m.seq = ::getpid();
  m.host = c.host.empty() ? before->host : c.host;
  m.process = c.process;
  m.command = c.command;
  if (!bus.publish(c.channel, m)) return app::kExitRuntimeError;
  const auto done = [&]() {
    const auto now = find();
    if (!now) return false;
    if (c.command == "stop") return now->state == "stopped";
    const bool up = now->state == "running" || now->state == "starting";
    return c.command == "restart" ? up && now->pid != before->pid : up;
  };
  const auto answer_deadline = Clock::now() + std::chrono::duration<double>(timeout);
  while (!done() && Clock::now() < answer_deadline && !app::stopRequested()) bus.handle(50);
  const auto now = find();
  if (!done()) {
    std::cout << fmt::format("{} {}: not done within {:.1f} s (now {}, pid {})\n", c.command, c.process, timeout,
                             now ? now->state : "?", now ? now->pid : -1);
    return kExitNoAnswer;
  }
  std::cout << fmt::format("{} {} on {}: {} (pid {})\n", c.command, c.process, now->host, now->state, now->pid);
  return app::kExitOk;
}

void addProcessCommands(CLI::App& app, ProcessCommands& pcs) {
  pcs.status = app.add_subcommand("status", "print every process on the bus: host, pid, state, restarts, CPU %, RSS, "
                                            "message rates, heartbeat age (from HEARTBEAT); then the fusion daemon's "
                                            "status and timing (FUSION_STATUS, FUSION_TIMING)");
  pcs.status->add_option("--listen", pcs.listen, "[s] to listen for heartbeats (two at least, for the rates)")
      ->check(app::positive())
      ->check(app::wallSeconds())
      ->capture_default_str();
  ProcCommand& pc = pcs.command;
  pcs.proc = app.add_subcommand("proc", "stop, start or restart a process of a running launcher by its name in the "
                                        "system file: stop|start|restart NAME [--host HOST]");
  pcs.proc->add_option("command", pc.command, "stop, start or restart")
      ->required()
      ->check(CLI::IsMember({"stop", "start", "restart"}));
  pcs.proc->add_option("name", pc.process, "the process's name in the system file")->required();
  pcs.proc->add_option("--host", pc.host, "the launcher's host (default: the one that shows the process)");
  pcs.proc->add_option("--channel", pc.channel, "the launchers' control_channel")->capture_default_str();
}

}  // namespace lcmloc::ctl
