#pragma once
// lcmloc-evaluate as a library: its options and its run (the program is a thin main).
// Scores the estimates recorded in any log (POSE, optionally every POSE_*) against the ground
// truth recorded with them: position / heading / drift errors, NEES against its chi-square
// bounds, gate statistics from GATE; writes report.json, PNG figures and, on request, TUM
// trajectory files for the evo tools. With --filters, also replays the log's sensor channels
// through the fusion daemon's code once per filter and scores those estimates too.
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/eval/trajectory_report.hpp"

namespace lcmloc::eval {

struct EvaluateCommand {
  std::string log_path, out_dir = "out/evaluate", tum_dir;
  std::string config_path;           ///< system config ("" = none): default channels and datum
  TrajectoryLogOptions lo;
  EvaluateOptions eo;
  TrajectoryPlotOptions po;
  std::vector<double> datum;
  bool no_plots = false, export_only = false;
  bool overwrite = false;  ///< --overwrite: replace an existing report directory / TUM files
  /// Filter types to replay from the log's sensor channels and score beside the recorded
  /// estimates (replay_filters.hpp); empty: nothing is replayed.
  std::vector<std::string> filters;
  /// The options whose default the config replaces unless they were given.
  CLI::Option* o_pose = nullptr;
  CLI::Option* o_truth = nullptr;
  CLI::Option* o_gate = nullptr;
};

/// lcmloc-evaluate's options (all but the common ones: --config, --log-level) into c.
void addEvaluateOptions(CLI::App& app, EvaluateCommand& c);

/// Runs lcmloc-evaluate; returns its exit code (0 done, 1 nothing to evaluate, 2 bad options or
/// config, 3 done from a damaged log).
int runEvaluate(EvaluateCommand c);

}  // namespace lcmloc::eval
