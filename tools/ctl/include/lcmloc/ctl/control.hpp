#pragma once
// lcmloc-ctl's work: sends one FUSION_CONTROL command to the fusion daemon and prints its answer
// (the "ack" or "refused" event on FUSION_STATUS), waiting a bounded time.
//
// The daemon applies commands in message-time order (like every input), so a command carries a
// utime: by default one reorder window after the newest ODOMETRY / IMU / POSE / FUSION_STATUS
// seen on the bus, i.e. just ahead of "now" in the daemon's time. (The newest POSE alone can lag
// the daemon's processing by fusion.output_every - 1 odometry periods: a command at it came too
// late.) An ODOMETRY or IMU time more than fusion.max_time_jump ahead of the daemon's own newest
// POSE / FUSION_STATUS is not taken: the daemon holds such an input as a possible time jump, and a
// command after a stray far-future message would wait for a time that never comes. Nor is the time
// of an answer to another command (it is that command's time, ahead of the inputs). The command's
// seq is unique (process id and clock), and the daemon's answer names it: several tools may send
// at once. The command is recorded by the logger like any message, and an offline replay of the
// log performs it at the same point.
#include <cstdint>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/fusion_control_t.hpp"

namespace lcmloc::ctl {

/// lcmloc-ctl's own exit codes, after the shared ones (app::ExitCode, 0 to 3).
inline constexpr int kExitNoAnswer = 4, kExitRefused = 5;

/// One command as given on the command line.
struct Command {
  enum Kind { Switch, Reset, SetPose } kind = Reset;
  std::string filter;                  ///< Switch: the filter type
  std::vector<std::string> params;     ///< Switch: KEY=VALUE items (dotted keys nest)
  std::string params_yaml;             ///< Switch: a YAML flow map instead of params
  std::vector<double> pose;            ///< SetPose: x [m], y [m], theta [rad]
  std::vector<double> stddev{0.1, 0.1, 0.05};  ///< SetPose: their 1-sigma
};

/// "a.b=v" items -> YAML flow map {a: {b: v}}; values are parsed as YAML (numbers, lists).
/// Throws CLI::ValidationError (a usage error) for an item without KEY=.
std::string paramsToYaml(const std::vector<std::string>& items);

/// The fusion_control_t of c (seq and utime are set by send()). Throws CLI::ValidationError.
lcmloc::fusion_control_t makeCommand(const Command& c);

/// Sends cmd on the bus at lcm_url at utime (< 0: one reorder window after the daemon's newest
/// time seen within timeout [s]) and prints the daemon's answer. Returns app::kExitOk
/// (acknowledged), kExitRuntimeError (no daemon on the bus), kExitRefused or kExitNoAnswer.
int send(const app::SystemConfig& cfg, const std::string& lcm_url, lcmloc::fusion_control_t cmd, double timeout,
         int64_t utime);

}  // namespace lcmloc::ctl
