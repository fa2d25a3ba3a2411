#pragma once
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::replay {

struct BenchOptions {
  double duration_s = 3600.0;  ///< message time of the synthetic log
  int repetitions = 3;
  std::string dir = "out/bench";
  bool keep_log = false;       ///< reuse dir/synthetic.lcmlog if it exists
  /// fusion.output_every of the batched rows (measured in the same run as the default rows);
  /// 1 = no batched rows.
  int output_every = 10;
  /// Only the cases with these keys (those of bench.json); empty: all.
  std::vector<std::string> cases;
};

/// Generates the synthetic log, measures read+decode, dead_reckoning and ukf_gated replay
/// (repetitions each, interleaved), prints medians and ratios, writes dir/bench.json.
int runBench(const simconfig::SimSystemConfig& cfg, const BenchOptions& opts);

}  // namespace lcmloc::replay
