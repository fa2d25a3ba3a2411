#pragma once
// Offline replay: reads an LCM log directly (logio::LogScanner, no network),
// feeds every event through the fusion daemon's own code (fusion::FusionDaemon over a LogBus,
// its intake on a reading thread and the rest on the caller's, ReplayOptions::read_ahead):
// the sensor channels and the recorded FUSION_CONTROL commands, in canonical order by message
// time (core::FusionEngine). The daemon's publications (POSE, POSE_<TYPE>, GATE, FUSION_STATUS)
// are written to an output log, byte for byte as the daemon publishes them live.
#include <functional>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/sim/scenario_config.hpp"

namespace lcmloc::replay {

struct ReplayOptions {
  std::string input;
  std::string output;              ///< "" = count only, write nothing
  /// Also copy the input events to the output (all channels except the daemon's outputs, the
  /// heartbeats and LCM_SELF_TEST), so the output log is complete for lcmloc-evaluate.
  bool with_inputs = false;
  /// Also write the control pose (channels.pose_control) the live daemon published: the input
  /// log's event order stands for the order the messages arrived in.
  bool control = false;
  double progress_period_s = 2.0;  ///< [s, wall] between progress lines (<= 0: none)
  /// Two threads: one reads the log and runs the daemon's intake on each message (decoding,
  /// validation, the sequence check: fusion::DaemonIntake), the other the rest of the daemon
  /// (FusionDaemon::apply: the engine, the filters, the outputs), on the items in their order.
  /// false: both in the caller's thread. The outputs and the result are the same either way.
  bool read_ahead = true;
  std::function<bool()> stop;      ///< polled every 256 events (and before the first): true ends the replay early
};

struct ReplayResult {
  int64_t file_size = 0;
  int64_t events_read = 0;         ///< intact events in the input log
  int64_t old_outputs = 0;         ///< recorded daemon outputs in the input (ignored)
  int64_t dispatched = 0;          ///< events handed to the daemon (its input channels)
  int64_t messages_in = 0;         ///< as the daemon counts them (FUSION_STATUS.messages_in)
  int64_t used = 0;                ///< processed by the filter (FUSION_STATUS.messages_used)
  int64_t rejected = 0;            ///< refused inputs (too old, invalid, undecodable)
  int64_t gaps = 0;                ///< messages missing according to seq gaps
  int64_t written = 0;             ///< events written (outputs + copied inputs)
  int64_t copied = 0;              ///< of those, copied inputs
  std::map<std::string, int64_t> written_per_channel;
  std::string final_filter;
  bool damaged = false, interrupted = false;
  /// Why the output log could not be written ("": it was): the replay stopped there.
  std::string write_error;
  int64_t bytes_unreadable = 0;
  std::vector<logio::LogIssue> issues;  ///< damage of the input, with event index and byte offset
  double seconds = 0;              ///< wall time of the replay
  /// CPU time [s] of each side (ReplayOptions::read_ahead: of each thread, otherwise of each part
  /// of the one): reading (the log, the bus's dispatch, the daemon's intake) and applying (the
  /// rest of the daemon, the outputs). With two threads, the busier one sets the replay's rate.
  double reading_cpu_s = 0, applying_cpu_s = 0;
  /// ReplayOptions::read_ahead: times either thread slept waiting for the other (for a block to
  /// fill, or a block to read into); each sleep ends in a wake-up.
  int64_t handoff_sleeps = 0;
};

/// Replays opts.input with cfg (filter, shadows, channels, reorder window). Throws
/// std::runtime_error when the input cannot be opened or the output cannot be created,
/// std::invalid_argument / app::ConfigError on a bad filter configuration.
ReplayResult replayLog(const app::SystemConfig& cfg, const ReplayOptions& opts);

/// Output channels of the daemon under cfg: POSE, POSE_CONTROL, POSE_<TYPE> of each shadow, GATE,
/// FUSION_STATUS.
bool isDaemonOutput(const app::ChannelConfig& ch, const std::string& channel);

/// A synthetic log (for the benchmark and tests): the vehicle drives laps of an oval track
/// (two straights joined by half circles) with markers along the first lap, for duration_s of
/// message time; the simulator's own models (lib/sim) produce ODOMETRY at the odometry
/// rate and MAGRULER detections. Event timestamps are message times.
struct SyntheticLogStats {
  int64_t odometry = 0, detections = 0, markers = 0;
  double distance_m = 0;
  int64_t first_utime = 0, last_utime = 0;
  bool stopped = false;  ///< `progress` asked to stop: the log ends early
};
struct OvalTrack {
  double straight = 40.0;   ///< [m]
  double radius = 25.0;     ///< [m] (gentle enough for the path follower to stay on the markers)
  double marker_spacing = 2.0;  ///< [m]
};
/// The scenario of the synthetic log (path, markers) from base: the same oval for the replay's
/// marker map. laps is chosen so that the track is long enough for duration_s.
sim::ScenarioConfig ovalScenario(const sim::ScenarioConfig& base, const OvalTrack& track, double duration_s);
/// progress (optional) is called every 10 s of message time with the fraction of duration_s
/// written; it returns false to stop writing there.
SyntheticLogStats writeSyntheticLog(const sim::ScenarioConfig& scenario, double duration_s, const std::string& path,
                                    const app::ChannelConfig& channels,
                                    const std::function<bool(double)>& progress = {});

}  // namespace lcmloc::replay
