#pragma once
// The fusion engine's settings (config/*.yaml, fusion.*) and its counters.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/landmark_fix.hpp"

namespace lcmloc::core {

/// Gate on the three-landmark fix (fusion.landmark_fix): each filter refuses a fix whose
/// Mahalanobis distance to its own pose, (fix - pose)' (P + R)^-1 (fix - pose) over (x, y, theta),
/// exceeds the chi-square (3 dof) quantile at `probability` (decision reason "gate", event
/// "fix_refused"): a wrong landmark association, a fix of another place. After `lockout_rejections`
/// consecutive refused fixes a filter takes the next one whatever its distance (decision reason
/// "fix_lockout", event "fix_lockout"): fixes that keep disagreeing with a filter say the filter is
/// the one that is lost.
struct LandmarkFixGate {
  double probability = 0.9999;  ///< in (0, 1) (0.9999 -> 21.1); 0 = no gate, every fix taken (seeds/004)
  int lockout_rejections = 2;   ///< 0 = never
};

/// Odometry gaps (fusion.max_odometry_gap, fusion.odometry_gap_accel, fusion.odometry_gap_yaw_rate;
/// docs/odometry_gap.md): two consecutive inputs of one odometry channel more than max_gap_us
/// apart in message time whose seq does not follow (an increment whose seq follows covers the
/// whole interval: a slow or paused sender lost nothing). Every filter is told
/// (Filter::bridgeOdometryGap) before the increment after the gap; event "odometry_gap".
struct OdometryGapConfig {
  int64_t max_gap_us = 100000;  ///< 0 = off
  double accel_std = 0.5;       ///< OdometryGap::accel_std [m/s^2]
  double yaw_rate_std = 0.05;   ///< OdometryGap::yaw_rate_std [rad/s]
  /// [us] The odometry sender's period (the daemon: fusion.odometry_period), for a resume gap: the
  /// first odometry input after initialize() more than max_gap_us after the state's time (a
  /// daemon started again from its checkpoint after a crash) is a gap too, bridged at the speed
  /// of that first increment over this period (its sender's previous message was not seen);
  /// 0 = not known: bridged at speed 0, the covariance grown all the same.
  int64_t resume_period_us = 0;
};

/// What is expected of one sensor channel (fusion.sensors; docs/horizon.md).
struct SensorExpectation {
  /// [us] How long after its utime a message of the channel arrives at most (a GNSS receiver:
  /// 50-200 ms): the horizon covers the largest (EngineConfig::horizonUs), so that such a message
  /// is fused in canonical order rather than refused as "too_old". >= 0.
  int64_t delay_us = 0;
  /// [us] Its period; > 0: watched: when kStopPeriods periods (and its delay) of message time of
  /// the other inputs pass without one of its inputs, event "sensor_stopped", and
  /// "sensor_resumed" at its next input. 0 = not watched.
  int64_t period_us = 0;
};

/// Periods of silence after which a watched sensor is said to have stopped.
inline constexpr int kStopPeriods = 5;

struct EngineConfig {
  FilterConfig filter;                 ///< initial active filter
  std::vector<std::string> shadow;     ///< shadow filter types (same parameters otherwise)
  /// The reorder window [us]: the horizon is at least this (horizonUs()).
  int64_t reorder_window_us = 50000;
  /// By channel name: each sensor's expected delay and period (none: delay 0, not watched).
  std::map<std::string, SensorExpectation> sensors;
  /// The memory bound of the horizon: inputs held at most. One more and the oldest is processed
  /// before its time (event "horizon_full", EngineCounters::released_early). >= 1.
  std::size_t max_queued = 20000;
  /// [us] The fusion horizon: the reorder window, or the largest expected delay of a sensor when
  /// larger. The canonical estimate is fused this far behind the newest input; an input older
  /// than what was released is refused ("too_old", with its lateness).
  int64_t horizonUs() const {
    int64_t h = reorder_window_us;
    for (const auto& [channel, s] : sensors) h = s.delay_us > h ? s.delay_us : h;
    return h;
  }
  /// Canonical order: by utime, then by the rank of the input's kind (kCanonicalRank: control <
  /// odometry < ruler < imu < gps < landmark < beacon < bearings); inputs of one kind on
  /// different channels are ordered by a stable hash of the channel name, then by seq.
  /// Output decimation (fusion.output_every): 1 = a state after every odometry message. N > 1 =
  /// a state after every N-th odometry message (and after every measurement, as always); the
  /// odometry in between is composed and applied with one time update by the filters that can
  /// (Filter::accumulate), always before the next measurement or command is processed.
  /// activeState() then does not include odometry composed since the last output.
  int output_every = 1;
  /// Landmark map (id -> x east, y north [m]) for three-landmark fixes from BearingsInput, and
  /// the fix's options (bearing noise default, condition limit). A BearingsInput is turned into
  /// a pose fix by damped least squares started from the active filter's pose and handed to
  /// every filter's applyFix through each filter's gate (fix_gate); refused (decision reason
  /// "bad_input" or "geometry", event "bad_input" or "fix_refused") on unknown ids, NaN, more than
  /// three bearings or the danger circle;
  /// fewer than three bearings (landmarks out of view) give decision reason "too_few_landmarks"
  /// and no event.
  std::map<int, Vec2> landmarks;
  landmark::FixOptions fix;
  LandmarkFixGate fix_gate;
  /// Time-jump guard (fusion.max_time_jump; 0 = off): an input whose utime is more than this
  /// ahead of, or behind, the newest input taken so far is held as suspect. kTimeJumpConfirm
  /// consecutive suspects on the same side within this of each other confirm a new time base
  /// (event "time_jump"): ahead, they are taken in order and nothing is lost (one message with a
  /// corrupt utime in the future would otherwise make every later input "too_old"); behind, the
  /// sources started over (a restarted simulator, a log played again into a running daemon): what
  /// is queued is processed, the filters start afresh from their configuration (the active type
  /// kept), as in a newly started daemon, and the suspects are taken. An input of the old time base
  /// drops the held suspects as outliers (event "too_new" or "too_old" each).
  int64_t max_time_jump_us = 1000000;
  OdometryGapConfig odometry_gap;
};

/// What the engine did with its inputs. too_new: inputs dropped by the time-jump guard
/// (EngineConfig::max_time_jump_us); accepted and rejected: the active filter's decisions;
/// released_early: inputs processed before their time at the horizon's memory bound.
struct EngineCounters {
  int64_t processed = 0, too_old = 0, too_new = 0, accepted = 0, rejected = 0, released_early = 0;
};

/// The inputs of one channel refused as later than the horizon (not duplicates): how many, and
/// the largest lateness [us]: how long after its time it came (the newest input's time then minus
/// its utime), the expected delay (fusion.sensors.<key>.delay) that would have fused it.
struct LateInputs { int64_t count = 0, max_lateness_us = 0; };

}  // namespace lcmloc::core
