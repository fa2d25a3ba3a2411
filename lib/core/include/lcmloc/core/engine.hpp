#pragma once
// The fusion engine: canonical ordering + the active filter (+ shadow filters) + control
// commands. Middleware-free; the daemon feeds it from LCM, the offline replay from a log file,
// and both therefore compute the same outputs for the same input messages in the same order.
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "lcmloc/core/channel_name.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/landmark_fix.hpp"
#include "lcmloc/core/reorder.hpp"
#include "lcmloc/core/time_guard.hpp"

namespace lcmloc::core {

/// Control commands (fusion_control_t).
struct SwitchFilter { FilterConfig config; };           ///< switch active filter (type + params)
struct ResetFilter {};                                   ///< back to the configured initial state
struct SetPose { Pose pose; Vec3 stddev; };              ///< re-initialise x, y, theta
using ControlCommand = std::variant<SwitchFilter, ResetFilter, SetPose>;

/// A value kept on the heap, copied deeply: an alternative larger than the odometry increment (a
/// ControlCommand carries a whole FilterConfig, an IMU sample three vectors and a name) does not
/// make every EngineInput large. EngineInputs are created, handed from the replay's reading
/// thread to its applying one, moved through the reorder window and destroyed once per message:
/// at 72 bytes (an odometry increment inline, everything else boxed) instead of 152, the replay's
/// item of a message spans under one and a half cache lines instead of two and a half, and half
/// as much memory is touched; a boxed input costs an allocation (tens of nanoseconds, for inputs
/// that take microseconds in the filters).
template <typename T>
class Boxed {
 public:
  Boxed(T value) : p_(std::make_unique<T>(std::move(value))) {}  // NOLINT: implicit on purpose
  Boxed(const Boxed& o) : p_(std::make_unique<T>(*o)) {}
  Boxed(Boxed&&) noexcept = default;
  Boxed& operator=(const Boxed& o) {
    if (this != &o) p_ = std::make_unique<T>(*o);
    return *this;
  }
  Boxed& operator=(Boxed&&) noexcept = default;
  const T& operator*() const { return *p_; }
  const T* operator->() const { return p_.get(); }

 private:
  std::unique_ptr<T> p_;
};

/// One input message, already converted and validated.
struct EngineInput {
  ChannelName channel;
  int64_t seq = 0;
  int64_t utime = 0;
  /// Alternatives are only ever appended (the index is part of the canonical tie-break).
  std::variant<OdometryInput, Boxed<RulerDetection>, Boxed<ControlCommand>, Boxed<ImuInput>, Boxed<GpsInput>,
               Boxed<LandmarkObservation>, Boxed<BeaconRange>, Boxed<BearingsInput>>
      payload;
};

/// The reorder window's move of an input into a reused slot (ReorderBuffer, assignSlot): an
/// odometry input into a slot that held one, as in nearly every slot, copies the increment
/// directly instead of going through the variant's move assignment (a jump table per message).
/// Every field of EngineInput is assigned here.
inline void assignSlot(EngineInput& slot, EngineInput&& in) {
  slot.channel = in.channel;
  slot.seq = in.seq;
  slot.utime = in.utime;
  auto* to = std::get_if<OdometryInput>(&slot.payload);
  const auto* from = std::get_if<OdometryInput>(&in.payload);
  if (to && from)
    *to = *from;
  else
    slot.payload = std::move(in.payload);
}

/// Outputs are delivered through callbacks, in processing order.
struct EngineOutputs {
  /// (filter name, state) after every processed odometry or ruler input, and after every IMU
  /// or GPS input a filter used, for the active filter (is_active = true) and each shadow.
  std::function<void(const std::string& filter, bool is_active, const FilterState&)> on_state;
  std::function<void(const std::string& filter, bool is_active, const GateDecision&)> on_decision;
  /// Events worth a human's attention: ("ack"|"refused"|"lockout"|"recovered"|"too_old"|
  /// "too_new"|"time_jump"|"fix"|"fix_refused"|"fix_lockout"|"imu_saturated"|"bad_input"|"odometry_gap", detail). "bad_input": an odometry increment, IMU sample or GPS fix (with a fix) with a NaN/Inf field
  /// (skipped).
  std::function<void(const std::string& event, const std::string& detail, int64_t utime)> on_event;
};

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

struct EngineConfig {
  FilterConfig filter;                 ///< initial active filter
  std::vector<std::string> shadow;     ///< shadow filter types (same parameters otherwise)
  int64_t reorder_window_us = 50000;
  /// Canonical tie-break rank at equal utime: control < odometry < ruler < imu < gps < landmark <
  /// beacon (by payload type);
  /// inputs of one type on different channels are ordered by a stable hash of the channel name,
  /// then by seq.
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


class FusionEngine {
 public:
  /// Throws std::invalid_argument when the initial or a shadow filter config is invalid.
  FusionEngine(EngineConfig cfg, MarkerMap map, EngineOutputs out);
  ~FusionEngine();
  FusionEngine(FusionEngine&&) noexcept;
  FusionEngine& operator=(FusionEngine&&) noexcept;
  /// Queues an input; processes whatever the reorder window releases. Returns false (and emits
  /// "too_old") when the input is older than what was already processed; a refused input is
  /// left as it was. An input beyond the time-jump guard is held (true) and taken or dropped
  /// later (see EngineConfig::max_time_jump_us). A command waits in the window until an input
  /// other than a command is newer than it by the window (or flush()); one more than
  /// max_time_jump_us ahead of the newest input is refused ("too_new").
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
  /// too_new: inputs dropped by the time-jump guard (EngineConfig::max_time_jump_us).
  struct Counters { int64_t processed = 0, too_old = 0, too_new = 0, accepted = 0, rejected = 0; };
  Counters counters() const;
 private:
  /// Past the time-jump guard: into the reorder window; an input that does not `advance` (a
  /// command) does not move the window's time.
  bool take(EngineInput&& in, bool advance = true);
  bool pushCommand(EngineInput&& in);  ///< push() of a control command
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lcmloc::core
