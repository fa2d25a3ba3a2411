// lcmloc-evaluate --filters (see replay_filters.hpp).
#include "lcmloc/eval/replay_filters.hpp"

#include <filesystem>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "lcmloc/replay/replay.hpp"

namespace lcmloc::eval {

std::string replayedName(const std::string& type) { return "replay:" + type; }

void addReplayedFilters(TrajectoryLog& log, const std::string& path, const app::SystemConfig& cfg,
                        const std::vector<std::string>& types, const std::string& work_dir,
                        const std::atomic<bool>* stop) {
  app::checkFilterList(types, "--filters", "filters");
  std::vector<app::SystemConfig> configs;
  for (const auto& type : types) {  // every filter checked before the first replay
    app::SystemConfig c = cfg;
    YAML::Node n;
    n["type"] = type;
    c.fusion.filter = app::parseFilterConfig(n, cfg.fusion.filter, "--filters", "fusion.filter");
    c.fusion.shadow.clear();
    c.fusion.output_every = 1;  // every estimate is scored
    configs.push_back(c);
  }
  std::filesystem::create_directories(work_dir);
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (stop && stop->load()) break;
    const auto& c = configs[i];
    replay::ReplayOptions ro;
    ro.input = path;
    ro.output = work_dir + "/replay_" + types[i] + ".lcmlog";
    ro.progress_period_s = 0;
    ro.stop = [stop] { return stop && stop->load(); };
    const auto result = replay::replayLog(c, ro);
    if (!result.write_error.empty()) throw std::runtime_error("replay of " + types[i] + ": " + result.write_error);
    TrajectoryLogOptions o;
    o.pose_channel = c.channels.pose;
    o.gate_channel = c.channels.gate;
    o.truth_channel = "";  // the truth is the recorded one
    const auto out = readTrajectoryLog(ro.output, o, stop);
    std::error_code ec;
    std::filesystem::remove(ro.output, ec);
    EstimateTrack track = out.tracks.front();
    track.channel = replayedName(types[i]);
    log.tracks.push_back(std::move(track));
    for (auto g : out.gates) {
      g.filter = replayedName(g.filter);
      log.gates.push_back(std::move(g));
    }
  }
}

}  // namespace lcmloc::eval
