#pragma once
// The lock-out and recovery timeline of a pose track (lcmloc-evaluate): the spans of each
// pose_t status (tracking, dead reckoning, lock-out, uninitialized) and the re-localizations
// (gate decisions "relocalized") of the track's filters. In report.json, the summary and a
// figure, so that a run that went wrong shows when and for how long.
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lcmloc/eval/trajectory.hpp"

namespace lcmloc::eval {

/// Consecutive estimates of one status; it lasts until the next span's first estimate (the
/// last span: until the track's last estimate).
struct StatusSpan {
  int status = 0;  ///< pose_t STATUS_*
  int64_t from_utime = 0, to_utime = 0;
  int64_t estimates = 0;
  double seconds() const { return (to_utime - from_utime) * 1e-6; }
};

struct Relocalization {
  int64_t utime = 0;
  std::string filter, sensor;
};

struct StatusTimeline {
  std::string channel;
  std::vector<StatusSpan> spans;
  int lockouts = 0;                    ///< spans in STATUS_LOCKOUT
  double lockout_s = 0, longest_lockout_s = 0, dead_reckoning_s = 0;
  std::vector<Relocalization> relocalizations;  ///< of the track's filters, in time order
  /// Left STATUS_OK at some time, or re-localized.
  bool eventful() const;
};

/// The name of a pose_t status ("ok", "dead_reckoning", "lockout", "uninitialized", or the number).
std::string statusName(int status);

StatusTimeline statusTimeline(const EstimateTrack& track, const std::vector<GateRecord>& gates);

/// report.json's "status_timeline" of a track (times in seconds since t0 and in utime).
nlohmann::json statusTimelineJson(const StatusTimeline& t, int64_t t0);

/// One summary line, e.g. "POSE status: 2 lock-out(s), 3.1 s in lock-out (longest 2.0 s), 0.0 s
/// dead reckoning, 1 re-localization(s) at 12.3 s".
std::string statusSummary(const StatusTimeline& t, int64_t t0);

/// A figure of the status over time with the re-localizations marked (status_<stem>.png), when
/// the timeline is eventful; its name into figures.
void writeStatusPlot(std::ostream& gp, const StatusTimeline& t, int64_t t0, const std::string& dir,
                     const std::string& stem, std::vector<std::string>& figures);

}  // namespace lcmloc::eval
