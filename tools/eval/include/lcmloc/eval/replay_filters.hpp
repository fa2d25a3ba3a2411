#pragma once
// lcmloc-evaluate --filters: the log's sensor channels replayed through the fusion daemon's own
// intake and engine (replay::replayLog, as lcmloc-replay does) once per filter type, each
// replay's estimates and gate decisions scored beside the recorded ones. There is no other way
// from a log into the engine.
#include <atomic>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/eval/trajectory.hpp"

namespace lcmloc::eval {

/// Name of the track and of the gate decisions of the replay of filter type `type`.
std::string replayedName(const std::string& type);

/// Replays the log at `path` with cfg once per type (cfg.fusion.filter with that type, no
/// shadows, every pose published) and adds to `log` the track replayedName(type) and its gate
/// decisions (filter replayedName(type)). The replay's output log is written in work_dir and
/// removed. Throws app::ConfigError / std::invalid_argument on a bad filter list,
/// std::runtime_error when a replay fails; stop (optional) ends the replays early.
void addReplayedFilters(TrajectoryLog& log, const std::string& path, const app::SystemConfig& cfg,
                        const std::vector<std::string>& types, const std::string& work_dir,
                        const std::atomic<bool>* stop = nullptr);

}  // namespace lcmloc::eval
