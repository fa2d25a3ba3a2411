#include "launch_config.hpp"

#include <filesystem>
#include <fstream>

#include <spdlog/fmt/fmt.h>

#include "lcmloc/app/yaml_reader.hpp"

namespace lcmloc::launcher {

LaunchConfig loadLaunchConfig(const std::string& path) {
  namespace fs = std::filesystem;
  using app::ConfigError;
  const std::string text = app::readConfigFile(path, "system file");
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path, "", std::string("YAML error: ") + e.what());
  }
  LaunchConfig cfg;
  cfg.file = path;
  app::KeyReader r(doc, path, "");
  r.get("scenario", cfg.scenario);
  r.get("drain_time", cfg.drain_time, 0.0, 3600.0);
  r.get("stop_timeout", cfg.stop_timeout, 0.1, 3600.0);
  r.get("ready_timeout", cfg.ready_timeout, 0.0, 3600.0);
  r.get("restart_delay", cfg.restart_delay, 0.0, 3600.0);
  r.get("restart_delay_max", cfg.restart_delay_max, 0.0, 3600.0);
  r.get("status_period", cfg.status_period, 0.0, 3600.0);
  r.get("control_channel", cfg.control_channel);
  r.get("run_dir", cfg.run_dir);
  r.get("heartbeat_timeout", cfg.heartbeat_timeout, 0.0, 3600.0);
  if (cfg.heartbeat_timeout > 0.0 && cfg.heartbeat_timeout < kMinHeartbeatTimeout)
    throw ConfigError(path, "heartbeat_timeout",
                      fmt::format("{} s is too short: 0 (off) or at least {} s (every process publishes HEARTBEAT "
                                  "once per second; one late or lost heartbeat must not count as a hang)",
                                  cfg.heartbeat_timeout, kMinHeartbeatTimeout));
  r.get("recv_buf_size", cfg.recv_buf_size, 0, 1 << 30);
  if (cfg.recv_buf_size > 0 && cfg.recv_buf_size < 65536)
    throw ConfigError(path, "recv_buf_size",
                      std::to_string(cfg.recv_buf_size) + " bytes: 0 (URL as given) or at least 65536");
  YAML::Node procs = r.child("processes");
  if (!procs || !procs.IsSequence() || procs.size() == 0)
    throw ConfigError(path, "processes", "expected a non-empty list of {name, executable, args, until_exit, restart, critical}");
  for (std::size_t i = 0; i < procs.size(); ++i) {
    const std::string kp = "processes[" + std::to_string(i) + "]";
    ProcessSpec p;
    app::KeyReader pr(procs[i], path, kp);
    pr.get("name", p.name);
    pr.get("executable", p.executable);
    pr.getStrings("args", p.args);
    pr.get("until_exit", p.until_exit);
    pr.get("restart", p.restart, 0, 1000000);
    pr.get("critical", p.critical);
    pr.finish();
    if (p.executable.empty()) throw ConfigError(path, kp + ".executable", "missing");
    if (p.until_exit && !p.critical)
      throw ConfigError(path, kp + ".critical",
                        "false with until_exit: true: the until_exit process ends the run, it must be critical");
    if (p.name.empty()) p.name = p.executable;
    for (std::size_t j = 0; j < cfg.processes.size(); ++j)
      if (cfg.processes[j].name == p.name)  // the summary, heartbeats and errors name processes
        throw ConfigError(path, kp + ".name",
                          "'" + p.name + "' is also the name of processes[" + std::to_string(j) +
                              "] (the executable's name when none is given): give each process its own name");
    cfg.processes.push_back(p);
  }
  r.finish();
  if (cfg.control_channel.empty()) throw ConfigError(path, "control_channel", "empty: give a channel name");
  if (!cfg.run_dir.empty() && fs::path(cfg.run_dir).is_relative())
    cfg.run_dir = (fs::path(path).parent_path() / cfg.run_dir).lexically_normal().string();
  if (!cfg.scenario.empty() && fs::path(cfg.scenario).is_relative())
    cfg.scenario = (fs::path(path).parent_path() / cfg.scenario).lexically_normal().string();
  return cfg;
}

}  // namespace lcmloc::launcher
