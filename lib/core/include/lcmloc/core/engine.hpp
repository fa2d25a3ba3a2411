#pragma once
// The fusion engine: middleware-free; the daemon feeds it from LCM, the offline replay from a
// log file, and both therefore compute the same outputs for the same input messages in the same
// order. It wires small parts, each owning its state:
//   InputOrder        time-jump guard and reorder window: inputs in canonical order
//   OdometryGaps      per-channel odometry tracks, gaps found and bridged
//   FilterBank        the active filter and the shadows, switch, start afresh
//   OutputDecimation  a state after every N-th odometry message (output_every)
//   LandmarkFixStage  three-landmark fixes through each filter's gate
//   Commands          switch, reset, set_pose, and their answers
//   ControlPredictor  the control pose: the active state and the motion still in the window
// A new time base (time went back) starts every part afresh.
#include <map>
#include <memory>
#include <string>

#include "lcmloc/core/engine_config.hpp"
#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::core {

class FusionEngine {
 public:
  /// Throws std::invalid_argument when the initial or a shadow filter config is invalid, or the
  /// fix gate or odometry gap settings are.
  FusionEngine(EngineConfig cfg, MarkerMap map, EngineOutputs out);
  ~FusionEngine();
  FusionEngine(FusionEngine&&) noexcept;
  FusionEngine& operator=(FusionEngine&&) noexcept;
  /// Queues an input; processes whatever the reorder window releases. Returns false (and emits
  /// "too_old") when the input is older than what was already processed; a refused input is
  /// left as it was. An input beyond the time-jump guard is held (true) and taken or dropped
  /// later (see EngineConfig::max_time_jump_us). A command waits in the window until an input
  /// other than a command is newer than it by the window (or flush()); one more than
  /// max_time_jump_us ahead of the newest input is refused ("too_new"). An odometry input
  /// taken is followed by the control pose (EngineOutputs::on_control, when set), and so is an IMU
  /// input when a filter (active or shadow) uses the IMU.
  bool push(EngineInput&& in);
  bool push(const EngineInput& in) { return push(EngineInput(in)); }
  /// Processes everything still queued (end of log / shutdown).
  void flush();
  /// Starts every filter (active and shadows) from state, mapped where the states differ
  /// (process-level hand-over: the last POSE of a previous daemon, or a checkpoint). The first
  /// odometry input more than the odometry gap limit after state.utime is a resume gap
  /// (OdometryGapConfig::resume_period_us).
  void initialize(const FilterState& state);
  std::string activeFilter() const;
  FilterState activeState() const;
  using Counters = EngineCounters;
  Counters counters() const;
  /// The inputs refused as later than the horizon, by channel (duplicates not counted).
  const std::map<std::string, LateInputs>& lateInputs() const;
  /// [us] The horizon (EngineConfig::horizonUs()).
  int64_t horizonUs() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lcmloc::core
