#pragma once
// lcmloc-landmark-experiment's work after its command line: the Monte Carlo of Fig. 5 (run), or
// the VISION observations of a recorded log solved against its GROUND_TRUTH (runObservations);
// report.json and figures in the output directory, a summary table on stdout.
#include <cstdint>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/landmark_experiment/experiment.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::landmark_experiment {

struct CommandOptions {
  std::string output = "out/landmark_experiment";  ///< output directory
  bool overwrite = false;   ///< replace the files of a directory that is not empty
  uint64_t seed = 0;        ///< 0: vision.seed, else derived from scenario.seed
  double heading_arcmin = Options().ins_heading_error / sim::kArcSec / 60.0;  ///< INS heading error [arcmin]
  std::vector<double> ins_offset{Options().ins_offset.x(), Options().ins_offset.y()};  ///< east, north [m]
  std::vector<double> off_centre{Options().off_centre.x(), Options().off_centre.y()};  ///< of the circumradius
  std::string log;          ///< a recorded run to solve instead of the Monte Carlo ("" = none)
  Options experiment;       ///< runs, distance (the rest is filled from the fields above and the config)
};

/// VISION observations of a log with the GROUND_TRUTH pose of the same utime. Undecodable or
/// non-finite messages are counted and skipped; a VISION message with no truth at its time too.
/// A damaged log is read up to and past the damage (eval's reader); each damaged place is logged
/// and *damaged set. Throws std::runtime_error when no observation has truth.
std::vector<Observation> readObservations(const std::string& path, const app::ChannelConfig& ch, bool* damaged);

/// Runs the experiment with cfg's `vision` (and `landmarks` for a log). Throws ConfigError (an
/// off-centre position outside 0.9 circumradius, a log without a map), UsageError (an existing
/// output without overwrite). Returns app::kExitOk, or kExitInputDamaged for a damaged log.
int runCommand(const simconfig::SimSystemConfig& cfg, CommandOptions o);

}  // namespace lcmloc::landmark_experiment
