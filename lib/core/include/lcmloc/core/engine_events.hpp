#pragma once
// The fusion engine's outputs: states, gate decisions and events. An event is typed, a kind and
// the fields of what happened; eventText() gives its words (the detail of a FUSION_STATUS
// message) where it leaves the program.
#include <climits>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <variant>
#include <vector>

#include "lcmloc/core/filter.hpp"

namespace lcmloc::core {

/// What happened (eventName(): the FUSION_STATUS event).
enum class EventKind {
  Ack,           ///< a command was applied
  Refused,       ///< a command was not
  Lockout,       ///< the active filter entered its lock-out
  Recovered,     ///< the active filter accepted a measurement again
  Ambiguous,     ///< the marker taken after an odometry gap may be a neighbour
  Restarted,     ///< a filter started again from its configured initial state
  TooOld,        ///< an input came too late (dropped)
  TooNew,        ///< an input is too far ahead (dropped)
  TimeJump,      ///< a new time base
  BadInput,      ///< an input with a non-finite field, or a landmark fix that cannot be made
  OdometryGap,   ///< an odometry gap was bridged
  ImuSaturated,  ///< IMU samples beyond the accelerometer's range (not used)
  Fix,           ///< the active filter took a landmark fix
  FixRefused,    ///< a landmark fix refused (geometry, or a filter's gate)
  FixLockout,    ///< a filter took a landmark fix after refusing several in a row
  Relocalized,   ///< the active filter re-localized from measurements its gate had refused
  HorizonFull,   ///< the horizon held EngineConfig::max_queued inputs: the oldest released early
  SensorStopped, ///< a watched sensor channel fell silent (SensorExpectation::period_us)
  SensorResumed, ///< a silent sensor channel delivered again
};
/// "ack", "refused", "lockout", "recovered", "ambiguous", "restarted", "too_old", "too_new",
/// "time_jump", "bad_input", "odometry_gap", "imu_saturated", "fix", "fix_refused", "fix_lockout",
/// "relocalized", "horizon_full", "sensor_stopped", "sensor_resumed".
const char* eventName(EventKind kind);

/// The input an event is about.
struct InputRef {
  std::string channel;
  int64_t seq = 0;
  int64_t utime = 0;
};

/// The fields of each event (EngineEvent::fields).
namespace events {
/// too_old: the horizon (reorder window) refused the input: a duplicate, or older than what was
/// processed. newest: the newest input's time when it came (its lateness: newest - its utime);
/// horizon_us: EngineConfig::horizonUs().
struct Late {
  InputRef input;
  bool duplicate = false;
  int64_t processed_utime = 0;
  int64_t newest = INT64_MIN;
  int64_t horizon_us = 0;
};
/// horizon_full: the horizon held max_queued inputs, the oldest (input) was released before its
/// time; early: inputs released early so far. One event per stretch of a full horizon.
struct ReleasedEarly { InputRef input; std::size_t max_queued = 0; int64_t horizon_us = 0; int64_t early = 0; };
/// sensor_stopped (stopped) or sensor_resumed: the channel's last input was at last_utime; newest
/// is the newest input's time (stopped) or the resuming input's (resumed).
struct SensorSilence {
  std::string channel;
  bool stopped = true;
  int64_t last_utime = 0, newest = 0, period_us = 0, limit_us = 0;
};
/// too_old (behind) or too_new (ahead): an input the time-jump guard held, and the old time base
/// went on. odometry_utime: ahead, the last odometry input when the odometry stopped more than
/// the guard before it (the odometry is missing, not this input); INT64_MIN otherwise.
struct Outlier { InputRef input; bool ahead = false; int64_t newest = 0; int64_t odometry_utime = INT64_MIN; };
/// too_new: a command beyond the time-jump guard.
struct CommandAhead { InputRef input; int64_t newest = 0; };
/// time_jump: a new time base from `first` on, after newest; back: the sources started over and
/// the filters restarted (restarted: the active filter).
struct TimeJump {
  InputRef first;
  int64_t newest = 0;
  int64_t confirm_span_us = 0;
  bool back = false;
  std::string restarted;
};
/// lockout: consecutive gate rejections, covariance inflated.
struct Lockout { std::string filter; };
/// recovered: out of a lock-out, or (after_gap) the first accepted measurement after a gap.
struct Recovered { std::string filter; bool after_gap = false; };
/// ambiguous: the position spread [m, 3 sigma] after the gap exceeds half the marker spacing [m].
struct Ambiguous { std::string filter; double spread = 0, spacing = 0; };
/// restarted: cause empty: the filter's state became non-finite; otherwise why its state could
/// not take the fix `then_applied` (the fix's source), applied after the restart.
struct Restarted { std::string filter; std::string cause; std::string then_applied; };
/// bad_input: a non-finite field in what ("odometry", "IMU sample", ...).
struct NonFinite { InputRef input; std::string what; };
/// bad_input or fix_refused: a landmark fix that cannot be made, and why.
struct FixNotMade { InputRef input; std::string why; };
/// fix_refused: a filter's gate refused the fix (its Mahalanobis distance above the gate).
struct FixGated { InputRef input; std::string filter; double distance = 0, gate = 0; int in_a_row = 0; };
/// fix_lockout: the filter took the fix after `after` refused in a row.
struct FixLockout { InputRef input; std::string filter; int after = 0; };
/// fix: the active filter took a landmark fix; moved: fix minus the pose before.
struct Fix { InputRef input; Vec3 pose = Vec3::Zero(), moved = Vec3::Zero(); double condition = 0; };
/// imu_saturated: the first saturated sample of a stretch; samples: so far, of the active filter.
struct ImuSaturated { InputRef input; double accel = 0, limit = 0; std::string filter; int64_t samples = 0; };
/// odometry_gap: every filter bridged a gap before `input` (bridged: each filter's account). resume:
/// the first odometry after initialize() (period_us: its sender's period); otherwise the channel's
/// previous input was previous_seq.
struct GapBridged {
  InputRef input;
  int64_t previous_seq = 0;
  bool resume = false;
  OdometryGap gap;
  int64_t max_gap_us = 0;
  int64_t period_us = 0;
  std::vector<std::string> bridged;
};
/// relocalized: the active filter took the pose of `evidence` (the input is its newest fix).
struct Relocalized { InputRef input; std::string filter; Relocalization evidence; };
/// ack or refused: the answer to a command. Switch: filter is the new type, previous the one
/// before; Reset: filter is the active filter; why: the refusal's reason, or (ack) a note.
struct Answer {
  enum class Command { Switch, Reset, SetPose };
  InputRef command;
  Command what = Command::Reset;
  std::string filter, previous, why;
};
}  // namespace events

using EventFields =
    std::variant<events::Late, events::Outlier, events::CommandAhead, events::TimeJump, events::Lockout,
                 events::Recovered, events::Ambiguous, events::Restarted, events::NonFinite, events::FixNotMade,
                 events::FixGated, events::FixLockout, events::Fix, events::ImuSaturated, events::GapBridged,
                 events::Answer, events::Relocalized, events::ReleasedEarly, events::SensorSilence>;

/// An event worth a human's attention at message time utime.
struct EngineEvent {
  EventKind kind;
  int64_t utime = 0;
  EventFields fields;
};

/// The event in words (FUSION_STATUS detail).
std::string eventText(const EngineEvent& e);

/// Outputs are delivered through callbacks, in processing order.
struct EngineOutputs {
  /// (filter name, state) after every processed odometry or ruler input, and after every IMU
  /// or GPS input a filter used, for the active filter (is_active = true) and each shadow.
  std::function<void(const std::string& filter, bool is_active, const FilterState&)> on_state;
  std::function<void(const std::string& filter, bool is_active, const GateDecision&)> on_decision;
  std::function<void(const EngineEvent&)> on_event;
  /// The control pose (ControlPredictor) after every odometry input the engine took, and every
  /// IMU input when a filter (active or shadow) uses the IMU, the
  /// moment it was pushed: the active filter's state with the inputs still waiting in the reorder
  /// window composed on top. Unset: none is computed.
  std::function<void(const FilterState&)> on_control;

  void event(EventKind kind, int64_t utime, EventFields fields) const {
    if (on_event) on_event(EngineEvent{kind, utime, std::move(fields)});
  }
  void decision(const std::string& filter, bool is_active, const GateDecision& d) const {
    if (on_decision) on_decision(filter, is_active, d);
  }
};

}  // namespace lcmloc::core
