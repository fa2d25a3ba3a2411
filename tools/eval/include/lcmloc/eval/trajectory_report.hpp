#pragma once
// Outputs of lcmloc-evaluate: report.json (keys in docs/evaluate.md), a summary table, PNG
// figures through gnuplot and the TUM trajectory export.
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lcmloc/eval/report.hpp"
#include "lcmloc/eval/trajectory.hpp"

namespace lcmloc::eval {

struct TrajectoryReportMeta {
  TrajectoryLogOptions log;
  EvaluateOptions eval;
  std::optional<ReplayComparison> live_vs_replay;  ///< --filters replayed the recorded estimates' filter
};

nlohmann::json makeTrajectoryReport(const TrajectoryLog& log, const std::vector<TrackScore>& scores,
                                    const GateStats& gates, const TrajectoryReportMeta& meta);

/// One line per track, the NEES verdicts, the gate groups, the decisions on announced faults,
/// the recorded estimates against their replay and the log's health.
void printTrajectorySummary(std::ostream& os, const TrajectoryLog& log, const std::vector<TrackScore>& scores,
                            const GateStats& gates, const std::optional<ReplayComparison>& live_vs_replay = {});

struct TrajectoryPlotOptions {
  int ellipse_every = 0;             ///< covariance ellipse at every k-th scored estimate (0: ~40 per track)
  double ellipse_sigma = 3.0;        ///< ellipse size in standard deviations
};

/// Per track: trajectory_<CH>.png (truth, estimate, ellipses), errors_<CH>.png (position and
/// heading error over time), nees_<CH>.png (NEES with the per-sample and mean bounds). Data
/// files and evaluate.gp stay in dir so a figure can be redrawn.
PlotResult writeTrajectoryPlots(const TrajectoryLog& log, const std::vector<TrackScore>& scores,
                                const TrajectoryPlotOptions& opt, const std::string& dir);

/// Per filter with gate decisions of a positive, finite NIS: gate_<FILTER>.png, the NIS of each
/// decision over time (accepted, rejected, on an announced fault) with the gate it was compared
/// with. Its commands go to the script gp, its data files into dir; the figures are appended.
void writeGatePlots(std::ostream& gp, const TrajectoryLog& log, int64_t t0, const std::string& dir,
                    std::vector<std::string>& figures);

/// One TUM line: "timestamp tx ty tz qx qy qz qw" with the timestamp in seconds (exact, six
/// decimals from the utime), z = 0 and the quaternion of a rotation by yaw about z.
std::string tumLine(int64_t utime, double x, double y, double yaw);

/// Writes the poses of a track (every estimate, also those outside the truth span) as TUM; of
/// several estimates with one utime only the last (TUM tools want unique timestamps). Returns
/// the lines written. Throws std::runtime_error on I/O failure.
std::size_t writeTum(const std::string& path, const std::vector<Estimate>& poses);
/// Writes the truth samples as TUM (heading 0 when the truth has none).
void writeTum(const std::string& path, const std::vector<TruthPose>& truth);

}  // namespace lcmloc::eval
