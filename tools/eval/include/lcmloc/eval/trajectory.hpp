#pragma once
// Scoring of recorded estimates against a reference (lcmloc-evaluate): reads the estimates
// (pose_t with covariance), the ground truth (ground_truth_t, or gps_fix_t about a datum) and
// the gate decisions (gate_decision_t) of any log through LogScanner, interpolates the truth
// onto the estimate times and computes position / heading / drift errors, NEES against its
// chi-square bounds and gate statistics. No LCM networking; plotting and TUM export in
// trajectory_report.hpp. Definitions: docs/evaluate.md.
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/core/chi2.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/scoring.hpp"
#include "lcmloc/logio/log_reader.hpp"

namespace lcmloc::eval {

// The evaluation reads logs with logio's reader and speaks of its issues and times.
using logio::badUtimeIssue;
using logio::kUtimeLimit;
using logio::LogIssue;
using logio::printBadUtime;
using logio::printIssues;
using logio::RawEvent;
using logio::secondsSince;
using logio::uniqueStems;
using logio::usableUtime;
using logio::utimeSpan;

/// One recorded estimate: (x, y, theta) and the top-left 3x3 block of its covariance.
struct Estimate {
  int64_t utime = 0;
  double x = 0, y = 0, theta = 0;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  bool has_cov = false;              ///< dim >= 3 and a finite covariance was recorded
  int status = 0;                    ///< pose_t STATUS_*
};

/// The estimates of one pose channel, sorted by utime.
struct EstimateTrack {
  std::string channel;
  std::vector<std::string> filters;  ///< filter names seen on the channel, in order of appearance
  std::vector<Estimate> poses;
  /// The newest estimate's self-calibration states (none when its filter has none).
  std::vector<core::CalibrationValue> calibration;
};

/// One reference sample. gps_fix_t truth has no heading, nor has ground_truth_t truth with a NaN
/// heading (a truth of position only).
struct TruthPose {
  int64_t utime = 0;
  double x = 0, y = 0, heading = 0;
  bool has_heading = true;
};

/// One gate_decision_t (core::GateRecord: mahalanobis field as nis).
using core::GateRecord;

struct TrajectoryLogOptions {
  std::string pose_channel = "POSE";
  bool all_pose_channels = false;    ///< also every other channel named POSE_*
  std::string truth_channel = "GROUND_TRUTH";
  std::string gate_channel = "GATE";
  std::string fault_channel = "FAULT_EVENTS";  ///< fault_event_t: measurements known to be faults
  /// landmark_obs_t: which observations carry no identity (landmark_id -1: the filter associates
  /// them with the nearest landmark; in a recording, e.g. other robots seen) ("" = none).
  std::string landmark_channel = "LANDMARKS";
  /// Needed only when the truth channel holds gps_fix_t (lat/lon -> local x east, y north).
  std::optional<bus::Datum> datum;
};

/// One fault_event_t: the measurement (channel, measurement_seq) is a known fault.
struct AnnouncedFault {
  int64_t utime = 0;
  std::string kind, channel;
  int64_t measurement_seq = -1;
};

struct TrajectoryLog {
  std::string path;
  int64_t file_size = 0, events_read = 0, bytes_unreadable = 0;
  bool damaged = false, interrupted = false;
  std::map<std::string, int64_t> channel_counts;
  std::map<std::string, int64_t> undecodable;  ///< per pose, truth or gate channel: messages not of its type
  std::vector<EstimateTrack> tracks; ///< the pose channel first (even when empty), then POSE_* by name
  std::vector<TruthPose> truth;      ///< sorted by utime, one sample per utime
  std::string truth_type;            ///< "ground_truth_t", "gps_fix_t" or "" (none decoded)
  std::vector<GateRecord> gates;     ///< in log order
  std::vector<AnnouncedFault> faults;  ///< in log order
  /// Observations on the landmark channel: their count, and the (channel, seq) of those without
  /// an identity (landmark_id < 0).
  std::string landmark_channel;      ///< TrajectoryLogOptions::landmark_channel
  int64_t landmark_observations = 0;
  std::vector<std::pair<std::string, int64_t>> unknown_identity;
  std::vector<LogIssue> issues;      ///< damage and undecodable/invalid messages, in file order
  int64_t bad_utime = 0;             ///< messages skipped for |utime| >= kUtimeLimit (also in issues)
};

/// Reads the log at path. Throws std::runtime_error when it cannot be opened. Damage and bad
/// messages are recorded in issues; everything readable is used. stop is polled between events.
/// progress (optional) is called about every 2^16 events with the bytes consumed and the file size.
TrajectoryLog readTrajectoryLog(const std::string& path, const TrajectoryLogOptions& opt,
                                const std::atomic<bool>* stop = nullptr,
                                const std::function<void(int64_t, int64_t)>& progress = nullptr);

// ---------------------------------------------------------------------------------------------

struct EvaluateOptions {
  std::vector<double> segment_lengths{10.0, 50.0, 100.0};  ///< drift segments [m]
  /// An estimate between two truth samples further apart than this is not scored [s] (0 = any).
  double max_truth_gap_s = 1.0;
  double confidence = 0.95;          ///< two-sided probability of the chi-square intervals
};

/// Why an estimate was not interpolated.
enum class TruthMiss { kNone, kBefore, kAfter, kGap };

/// Truth at utime: linear in x, y; heading along the shortest angle. nullopt (and why) before
/// the first or after the last sample or between two samples more than max_gap_us apart
/// (max_gap_us <= 0: no limit).
std::optional<TruthPose> interpolateTruth(const std::vector<TruthPose>& truth, int64_t utime,
                                          int64_t max_gap_us, TruthMiss* why = nullptr);

// The statistics are the scoring library's (lcmloc/core/scoring.hpp).
using core::chi2QuantileAnyDof;
using core::ConsistencyStats;
using core::consistency;
using core::DriftStats;
using core::effectiveSampleSize;
using core::ErrorStats;
using core::errorStats;
using core::percentile;

/// One scored estimate.
struct ScoredPose {
  int64_t utime = 0;
  double x = 0, y = 0, theta = 0;
  double truth_x = 0, truth_y = 0, truth_heading = 0;
  double err_x = 0, err_y = 0, err = 0;
  double err_heading = 0;                ///< wrap(theta - truth heading) (0 without truth heading)
  double distance = 0;                   ///< truth path length from the first truth sample [m]
  double nees3 = -1, nees2 = -1;         ///< -1 when not computed
  Eigen::Matrix2d cov_xy = Eigen::Matrix2d::Zero();
  bool has_cov = false;
  bool after_skip = false;               ///< estimates right before this one were not scored
};

struct TrackScore {
  std::string channel;
  std::vector<std::string> filters;
  int64_t estimates = 0, scored = 0;
  int64_t before_truth = 0, after_truth = 0, in_truth_gap = 0;  ///< not scored, and why
  int64_t without_covariance = 0;        ///< scored, but no usable (positive definite) covariance
  int64_t first_utime = 0, last_utime = 0;  ///< estimate time span
  ErrorStats position;                   ///< |(x, y) error| [m]
  bool has_heading = false;
  ErrorStats heading;                    ///< |wrapped heading error| [rad]
  double path_length_m = 0;              ///< truth path length between first and last scored estimate
  double final_error_m = 0;
  double final_error_pct = 0;            ///< 100 * final error / path length (0 without a path)
  std::vector<DriftStats> drift;
  ConsistencyStats nees3, nees2;         ///< over (x, y, theta) and over (x, y)
  std::vector<ScoredPose> points;
  std::vector<core::CalibrationValue> calibration;  ///< the track's (EstimateTrack::calibration)
};

/// Scores one track; truth must be sorted by utime.
TrackScore scoreTrack(const EstimateTrack& track, const std::vector<TruthPose>& truth,
                      const EvaluateOptions& opt);

/// The decisions of one filter on measurements some of which are announced faults.
struct FaultGroup {
  std::string filter;
  core::FaultCounts counts;
};

/// Per filter (sorted by name), its gate decisions counted against the announced faults: a
/// decision is on a fault when its (sensor, measurement_seq) is a fault's (channel,
/// measurement_seq).
std::vector<FaultGroup> faultStatistics(const std::vector<GateRecord>& gates,
                                        const std::vector<AnnouncedFault>& faults);

/// The decisions of one filter on landmark observations, those of known identity apart from
/// those without one (landmark_id -1). An accepted observation without identity was associated
/// with a landmark by the filter: where the recording's unknown observations are distractors
/// (other robots, say), each one accepted is a wrong update.
struct IdentityGroup {
  std::string filter;
  int known_decided = 0, known_accepted = 0;
  int unknown_decided = 0, unknown_accepted = 0;
};

/// Per filter (sorted by name): a decision is on an observation without identity when its
/// (sensor, measurement_seq) is one of unknown; decisions on other sensors are not counted. Only
/// filters that decided on the landmark channel are listed.
std::vector<IdentityGroup> identityStatistics(const std::vector<GateRecord>& gates, const std::string& landmark_channel,
                                              const std::vector<std::pair<std::string, int64_t>>& unknown);

/// The recorded estimates against the replay of the same filter (lcmloc-evaluate --filters).
struct ReplayComparison {
  std::string filter;                ///< the filter the recorded poses name (the last one)
  int64_t matched = 0;               ///< recorded estimates with a replayed one at the same utime
  double max_diff_m = -1;            ///< largest position difference among them (-1: none matched)
};

/// Compares recorded with replayed at equal utime (the last estimate at each utime of each).
ReplayComparison compareTracks(const EstimateTrack& recorded, const EstimateTrack& replayed);

using core::GateGroup;
using core::GateStats;
using core::gateStatistics;

}  // namespace lcmloc::eval
