#pragma once
// Offline evaluation: replays the sensor inputs of a log through core::FusionEngine (the same
// engine the daemon runs) once per filter and scores each estimate against ground truth.
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/core/engine.hpp"
#include "lcmloc/eval/log_reader.hpp"

namespace lcmloc::eval {

/// Everything the replay needs besides the log.
struct EvalSetup {
  core::FilterConfig filter;          ///< parameters shared by every filter (type overridden)
  core::MarkerMap map;
  int64_t reorder_window_us = 50000;
  /// The rest of the engine's configuration, as the daemon has it (common::engineConfig: the
  /// time-jump guard, odometry gaps); filter, shadows, reorder window and output_every (1: every
  /// pose is scored) are set per run.
  core::EngineConfig engine;
  std::vector<std::string> filters{"dead_reckoning", "ukf", "ukf_gated"};
};

/// One scored estimate.
struct TrackPoint {
  int64_t utime = 0;
  double x = 0, y = 0, theta = 0;
  bool scored = false;                ///< ground truth available at utime
  double truth_x = 0, truth_y = 0;
  double err_x = 0, err_y = 0, err = 0;
};

/// One ruler measurement as a filter decided on it.
struct DecisionRecord {
  core::GateDecision decision;
  bool is_fault = false;              ///< matched a FAULT_EVENTS (channel, measurement_seq)
};

struct Metrics {
  int64_t samples = 0;                ///< estimates scored against ground truth
  double rmse_m = 0, max_error_m = 0, final_error_m = 0;
  int accepted = 0;                   ///< measurements that updated the state
  int rejected = 0;                   ///< measurements considered and refused (gate, no candidate, ...)
  int ignored = 0;                    ///< measurements a filter does not use (dead reckoning)
  int faults_total = 0;               ///< faults announced on FAULT_EVENTS
  int faults_rejected = 0;            ///< of those, rejected by this filter
  int faults_accepted = 0;            ///< of those, accepted by this filter
  int valid_rejected = 0;             ///< genuine marker detections rejected
  int lockouts = 0;                   ///< lock-out events reported by the engine
};

struct FilterRun {
  std::string name;
  std::vector<TrackPoint> track;
  std::vector<DecisionRecord> decisions;
  Metrics metrics;
};

struct LiveRun {
  std::string filter;                 ///< filter named by the POSE messages (last one)
  FilterRun run;
  /// Largest position difference between the live POSE and the replay of the same filter at
  /// equal utime (-1 when that filter was not replayed or no utime matched).
  double max_diff_to_replay_m = -1;
  int64_t matched_poses = 0;
};

struct Evaluation {
  std::vector<FilterRun> filters;     ///< in the order requested
  std::optional<LiveRun> live;
  double gate_threshold = 0;          ///< the gated filters' threshold (innovation dim 2)
  int64_t t0_utime = 0;               ///< time origin of the figures (first truth or input)
  struct FaultMark { FaultRecord fault; double marker_x = 0, marker_y = 0; bool located = false; };
  std::vector<FaultMark> faults;      ///< with where the faulty marker would lie
};

/// Ground truth interpolated at utime; nullopt outside the truth's time span (+- one sample).
std::optional<TruthSample> truthAt(const std::vector<TruthSample>& truth, int64_t utime);

/// Runs every filter of setup over data. Throws std::invalid_argument for an unknown filter.
Evaluation evaluate(const LogData& data, const EvalSetup& setup);

}  // namespace lcmloc::eval
