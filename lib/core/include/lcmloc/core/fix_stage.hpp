#pragma once
// The three-landmark fix (EngineConfig::landmarks, fix, fix_gate): bearings to three known
// landmarks make a pose fix (damped least squares started from the active filter's pose), which
// each filter takes through its own gate; a filter that refused lockout_rejections fixes in a row
// takes the next one whatever its distance.
#include <limits>
#include <map>
#include <string>

#include "lcmloc/core/engine_config.hpp"
#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/filter_bank.hpp"

namespace lcmloc::core {

class LandmarkFixStage {
 public:
  /// Throws std::invalid_argument when the gate's probability is not in [0, 1) or its
  /// lockout_rejections is negative.
  LandmarkFixStage(const EngineConfig& cfg, FilterBank& bank, const EngineOutputs& out, EngineCounters& counters);

  /// Bearings in (b): a fix for every filter, or a decision saying why not.
  void process(const EngineInput& in, const BearingsInput& b);

  /// Whether bearings can make a fix at all (the configuration has landmarks).
  bool usable() const { return !landmarks_.empty(); }
  /// The gate's threshold: chi-square (3 dof) at fix_gate.probability; +inf: none.
  double gate() const { return gate_; }
  /// Fixes the filter (FilterBank::key) refused in a row.
  int refusedInARow(const std::string& filter_key) const;
  /// The filter (FilterBank::key) starts its count again (a filter switched to).
  void forget(const std::string& filter_key) { refused_.erase(filter_key); }
  /// Every count starts again (the filters were moved or started over).
  void reset() { refused_.clear(); }

 private:
  const std::map<int, Vec2>& landmarks_;
  const landmark::FixOptions& options_;
  LandmarkFixGate gate_cfg_;
  FilterBank& bank_;
  const EngineOutputs& out_;
  EngineCounters& counters_;
  double gate_ = std::numeric_limits<double>::infinity();
  std::map<std::string, int> refused_;  ///< by FilterBank::key
};

}  // namespace lcmloc::core
