#pragma once
// lcmloc-ins-experiment's work after its command line: one run per start profile (run), the
// sensor log of the first run if asked, report.json and figures in the output directory
// (writeReport), a summary table on stdout.
#include <cstdint>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/ins_experiment/experiment.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::ins_experiment {

struct CommandOptions {
  std::string output = "out/ins";  ///< output directory
  bool overwrite = false;          ///< replace existing outputs (the directory's files, the log)
  std::string log;                 ///< the first run's sensor log (GROUND_TRUTH, IMU, ODOMETRY); "" = none
  std::vector<std::string> starts{"hard", "gentle"};  ///< start profiles, one run each
  double duration = 0;             ///< overrides ins_sim.duration when > 0 [s]
  uint64_t seed = 0;               ///< overrides ins_sim.seed when not 0
  Options experiment;              ///< calibration_stage, fixes (the fix settings come from the config)
};

/// Runs the experiment with cfg's ins_sim, fusion.filter (and vision, landmarks, fusion.fix for
/// fixes). Throws ConfigError (fixes without a landmark map), UsageError (an existing output
/// without overwrite). Returns app::kExitOk, or kExitConfigError for an unknown start.
int runCommand(const simconfig::SimSystemConfig& cfg, const CommandOptions& o);

}  // namespace lcmloc::ins_experiment
