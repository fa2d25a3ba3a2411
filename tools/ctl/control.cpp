// lcmloc-ctl's work (see control.hpp).
#include "lcmloc/ctl/control.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <optional>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::ctl {

/// "a.b=v" items -> YAML flow map {a: {b: v}}; values are parsed as YAML (numbers, lists).
std::string paramsToYaml(const std::vector<std::string>& items) {
  YAML::Node root(YAML::NodeType::Map);
  for (const auto& it : items) {
    const auto eq = it.find('=');
    if (eq == std::string::npos || eq == 0)
      throw CLI::ValidationError("--param", "expected KEY=VALUE, got '" + it + "'");
    const std::string key = it.substr(0, eq), value = it.substr(eq + 1);
    std::vector<std::string> path;
    std::size_t start = 0;
    for (std::size_t dot; (dot = key.find('.', start)) != std::string::npos; start = dot + 1)
      path.push_back(key.substr(start, dot - start));
    path.push_back(key.substr(start));
    // Walk down with fresh handles (yaml-cpp nodes are references).
    std::vector<YAML::Node> chain{root};
    for (std::size_t i = 0; i + 1 < path.size(); ++i) {
      YAML::Node next = chain.back()[path[i]];
      if (!next.IsMap()) next = YAML::Node(YAML::NodeType::Map);
      chain.back()[path[i]] = next;
      chain.push_back(chain.back()[path[i]]);
    }
    chain.back()[path.back()] = YAML::Load(value);
  }
  YAML::Emitter e;
  e.SetMapFormat(YAML::Flow);
  e.SetSeqFormat(YAML::Flow);
  e << root;
  return e.c_str();
}

lcmloc::fusion_control_t makeCommand(const Command& c) {
  lcmloc::fusion_control_t cmd{};
  if (c.kind == Command::Switch) {
    cmd.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER;
    cmd.filter = c.filter;
    if (!c.params_yaml.empty() && !c.params.empty())
      throw CLI::ValidationError("--param", "give --param or --params, not both");
    cmd.parameters = !c.params_yaml.empty() ? c.params_yaml : c.params.empty() ? "" : paramsToYaml(c.params);
  } else if (c.kind == Command::SetPose) {
    cmd.command = lcmloc::fusion_control_t::CMD_SET_POSE;
    for (int i = 0; i < 3; ++i) {
      cmd.pose[i] = c.pose[static_cast<std::size_t>(i)];
      cmd.pose_std[i] = c.stddev[static_cast<std::size_t>(i)];
    }
  } else {
    cmd.command = lcmloc::fusion_control_t::CMD_RESET;
  }
  return cmd;
}

int send(const app::SystemConfig& cfg, const std::string& lcm_url, lcmloc::fusion_control_t cmd, double timeout,
         int64_t utime) {
  // The command's seq tells its answer from those of other commands (several tools at once):
  // the process id in the low 22 bits (Linux's pid_max is at most 2^22), the wall clock in us
  // above them (40 bits: 12.7 days, then it wraps; seq only tells commands apart).
  const auto now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch()).count();
  cmd.seq = ((static_cast<int64_t>(now_us) & ((int64_t{1} << 40) - 1)) << 22) |
            (static_cast<int64_t>(::getpid()) & ((int64_t{1} << 22) - 1));
  const std::string tag = cfg.channels.control + " seq " + std::to_string(cmd.seq);

  bus::Bus bus(lcm_url);
  int64_t newest = -1;       // the daemon's own POSE / FUSION_STATUS
  bool daemon_seen = false;  // a POSE or FUSION_STATUS: sensors alone do not answer commands
  std::vector<int64_t> input_times;  // ODOMETRY / IMU while waiting (bounded by --timeout)
  bool sent = false;
  std::optional<lcmloc::fusion_status_t> answer;
  bus.subscribe<lcmloc::pose_t>(cfg.channels.pose, [&](const std::string&, const lcmloc::pose_t& m, int64_t) {
    newest = std::max(newest, m.utime);
    daemon_seen = true;
  });
  // The daemon's high-rate inputs: what it has received, not only what it has published.
  bus.subscribe<lcmloc::odometry_t>(cfg.channels.odometry, [&](const std::string&, const lcmloc::odometry_t& m,
                                                               int64_t) {
    if (!sent) input_times.push_back(m.utime);
  });
  bus.subscribe<lcmloc::imu_t>(cfg.channels.imu, [&](const std::string&, const lcmloc::imu_t& m, int64_t) {
    if (!sent) input_times.push_back(m.utime);
  });
  bus.subscribe<lcmloc::fusion_status_t>(
      cfg.channels.status, [&](const std::string&, const lcmloc::fusion_status_t& m, int64_t) {
        if (!sent) {
          // An answer to a command (another tool's) is at that command's time, which may be
          // ahead of the daemon's inputs: not the daemon's time.
          if (m.event == "ack" || m.event == "refused" || m.detail.find(cfg.channels.control) != std::string::npos)
            return;
          newest = std::max(newest, m.utime);
          daemon_seen = true;
          return;
        }
        // The daemon's answer (ack, refused, rejected_input) names the command: "CHANNEL seq N: ..."
        // or "CHANNEL seq N utime U: ...". Another command's answer names another seq.
        const bool mine = (m.event == "ack" || m.event == "refused" || m.event == "rejected_input") &&
                          (m.detail.find(tag + ":") != std::string::npos ||
                           m.detail.find(tag + " utime ") != std::string::npos);
        if (mine && !answer) answer = m;
      });
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
  if (utime < 0) {
    while (!daemon_seen && Clock::now() < deadline && !app::stopRequested()) bus.handle(50);
    bus.drain();
    if (!daemon_seen) {
      spdlog::error("no {} or {} on the bus within {:.1f} s: is lcmloc-fusion running and receiving inputs? "
                    "(or give --utime)", cfg.channels.pose, cfg.channels.status, timeout);
      return app::kExitRuntimeError;
    }
    const int64_t jump = std::llround(cfg.fusion.max_time_jump * 1e6);  // 0: no guard
    int64_t ignored = 0, ignored_max = 0;
    const int64_t daemon_newest = newest;
    for (const int64_t t : input_times) {
      int64_t ahead = 0;
      if (jump > 0 && (__builtin_sub_overflow(t, daemon_newest, &ahead) || ahead > jump)) {
        ++ignored;
        ignored_max = std::max(ignored_max, t);
        continue;
      }
      newest = std::max(newest, t);
    }
    if (ignored > 0)
      spdlog::warn("{} input message(s) more than fusion.max_time_jump ({:.3f} s) ahead of the daemon's newest "
                   "output (utime {}) not taken for the command's time (the newest at utime {})",
                   ignored, cfg.fusion.max_time_jump, daemon_newest, ignored_max);
    const int64_t window = std::max<int64_t>(1, std::llround(cfg.fusion.reorder_window * 1e6));
    // A stray message with a utime near INT64_MAX on the bus: no overflow into a negative time.
    if (__builtin_add_overflow(newest, window, &utime)) {
      spdlog::error("the newest message time on the bus ({}) is too close to the end of the int64 range for a "
                    "command after it: give --utime", newest);
      return app::kExitRuntimeError;
    }
  }
  cmd.utime = utime;
  sent = true;
  if (!bus.publish(cfg.channels.control, cmd)) return app::kExitRuntimeError;
  spdlog::info("sent to {} at utime {} (seq {})", cfg.channels.control, utime, cmd.seq);
  const auto answer_deadline = Clock::now() + std::chrono::duration<double>(timeout);
  while (!answer && Clock::now() < answer_deadline && !app::stopRequested()) bus.handle(50);
  if (!answer) {
    std::cout << fmt::format("no answer within {:.1f} s (the daemon applies a command once its inputs are newer "
                             "than the command by the reorder window)\n", timeout);
    return kExitNoAnswer;
  }
  std::string detail = answer->detail;  // without the "CHANNEL seq N: " naming this command
  if (const auto at = detail.find(tag + ": "); at != std::string::npos) detail.erase(at, tag.size() + 2);
  std::cout << fmt::format("{}: {} (filter {})\n", answer->event, app::printable(detail),
                           app::printable(answer->filter));
  return answer->event == "ack" ? app::kExitOk : kExitRefused;
}

}  // namespace lcmloc::ctl
