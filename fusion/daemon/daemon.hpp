#pragma once
// The fusion daemon: LCM in (the sensor inputs of inputs.hpp, FUSION_CONTROL), validation and
// conversion, core::FusionEngine, LCM out (POSE, POSE_<TYPE>, GATE, FUSION_STATUS, and with
// Options::control POSE_CONTROL).
// Bad input never stops it: each rejected message gets a log line (rate-limited) and a status
// event, and is counted.
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "inputs.hpp"
#include "timing.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/log_throttle.hpp"
#include "lcmloc/bus/convert.hpp"
#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/bus/seq_tracker.hpp"
#include "lcmloc/bus/input_limits.hpp"
#include "lcmloc/bus/stream_guard.hpp"
#include "daemon/reject_book.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::fusion {

/// One message as the daemon's intake (DaemonIntake) made it: decoded, validated, converted,
/// its seq checked. What the daemon then does with it (FusionDaemon::apply: counting, reporting,
/// the engine, the outputs) depends on the items alone, in their order: the offline replay runs
/// the intake on its reading thread, ahead of the rest, and gets what the daemon publishes live.
struct IntakeItem {
  enum class Kind : uint8_t {
    Input,        ///< for the engine (input)
    Rejected,     ///< refused (input.channel, seq, utime, why): status rejected_input
    Refused,      ///< a command refused: status refused (why: its detail; note: the log line)
    DecodeError,  ///< undecodable (input.channel, why): status rejected_input
    Nothing,      ///< counted, nothing else (a ruler reading without a detection)
    Held,         ///< another publisher's on the channel (stream): counted, status on detection
  };
  Kind kind = Kind::Nothing;
  bool seq_event = false;   ///< the sequence tracker found a gap, a restart or an ignored seq (gap)
  core::EngineInput input;  ///< channel, seq and utime always; the payload with Kind::Input
  bus::SeqGap gap;       ///< with seq_event: what the sequence tracker found
  bus::StreamVerdict stream;  ///< the channel's publisher (bus::StreamGuard)
  std::string why;          ///< Rejected, Refused, DecodeError: the reason
  std::string note;         ///< Refused: the log line
};

/// The daemon's first stage: decodes (the bus does), validates and converts each message, and
/// checks its channel's seq. Its only state is the sequence tracker, so it may run on another
/// thread than the rest of the daemon (the replay's reading thread).
class DaemonIntake {
 public:
  explicit DaemonIntake(const app::SystemConfig& cfg);
  /// Fills `out` (whatever it held before) with what a sensor message is: its seq checked, then
  /// converted by bus::toInput (an input, nothing, or rejected with why). One for every kind
  /// of sensor input (kSensorInputs).
  template <typename Lcm>
  void take(const std::string& ch, const Lcm& m, IntakeItem& out) {
    tracked(out, ch, m.seq, m.utime);
    out.why.clear();
    if (out.kind == IntakeItem::Kind::Held) return;
    switch (bus::toInput(m, bus::InputContext{ch, frame_}, out.input.payload, out.why)) {
      case bus::Converted::Input:
        out.why = limits_.check(out.input);
        out.kind = out.why.empty() ? IntakeItem::Kind::Input : IntakeItem::Kind::Rejected;
        return;
      case bus::Converted::Refused:
        out.kind = IntakeItem::Kind::Rejected;
        return;
      case bus::Converted::Nothing:  // counted, nothing else
        return;
    }
  }
  /// A FUSION_CONTROL command (not seq-tracked: every lcmloc-ctl sends on it with its own seq).
  void control(const std::string& ch, const lcmloc::fusion_control_t& m, IntakeItem& out);
  void decodeError(const std::string& ch, const std::string& why, IntakeItem& out);

 private:
  /// out for message (ch, seq, utime) of `kind`, its seq checked when tracked.
  void start(IntakeItem& out, IntakeItem::Kind kind, const std::string& ch, int64_t seq, int64_t utime);
  void tracked(IntakeItem& out, const std::string& ch, int64_t seq, int64_t utime);
  const app::SystemConfig& cfg_;
  bus::SeqTracker gaps_;
  bus::StreamGuard streams_;
  bus::LimitCheck limits_;
  bus::LocalFrame frame_;  ///< lat/lon of GPS fixes -> local metric frame (cfg.datum)
};

/// The daemon is written against bus::MessageBus: lcmloc-fusion runs it over LCM, the
/// offline replay (lcmloc-replay) over a log file, so both publish the same bytes.
class FusionDaemon {
 public:
  struct Options {
    /// Queue every input until release() (process-level hand-over: wait for the previous
    /// daemon's last POSE first). "started" is published by release() then.
    bool hold = false;
    /// Remember what it publishes on POSE, for checkEcho (live only).
    bool echo = false;
    /// Publish the control pose on channels.pose_control as each odometry or IMU input is taken
    /// (core::EngineOutputs::on_control). The canonical outputs are the same either way.
    bool control = false;
    /// Measure each message's delay and processing time on the wall clock into this (live only;
    /// nothing of it reaches the estimate). Null: nothing measured.
    DaemonTiming* timing = nullptr;
  };
  FusionDaemon(const app::SystemConfig& cfg, bus::MessageBus& bus);
  FusionDaemon(const app::SystemConfig& cfg, bus::MessageBus& bus, Options opts);
  /// What the intake makes of each message the bus hands over goes into the item `slot` returns
  /// for it, instead of to apply() (the offline replay: the bus dispatches, and the intake runs,
  /// on its reading thread; it apply()s the items in their order on its own). Empty: apply() at
  /// once, as live.
  void divert(std::function<IntakeItem&()> slot) { slot_ = std::move(slot); }
  /// The rest of the daemon for one message after the intake: counts it, reports what the intake
  /// found (sequence gaps, refusals), hands an input to the engine (moved out of item).
  void apply(IntakeItem& item);
  /// Ends the hold: starts every filter from init (if given; source says where it came from),
  /// drops the queued inputs that init already covers and processes the rest. Inputs arriving
  /// later that init covers are dropped too (counted, not rejected). Covered: utime <= init.utime,
  /// except an input more than fusion.max_time_jump older (a source that started over since
  /// init, e.g. a checkpoint of an earlier run). With saw_queued (init is the last POSE of the
  /// daemon handed over from, which received what was queued here), every queued input at or
  /// before init.utime is covered, however much older: they were queued while it ran.
  void release(const std::optional<core::FilterState>& init, const std::string& source, bool saw_queued = false);
  bool holding() const { return hold_; }
  /// A POSE received on the active output channel (live only: lcmloc-fusion subscribes to its
  /// own output, Options::echo): this daemon's own echo, or another publisher's, i.e. a second
  /// daemon on the bus, whose poses interleave with these. A foreign one is reported: a warning
  /// and the status event foreign_output (the first five, then one in 1000). Returns whether it
  /// was foreign. Own: a seq this daemon published on that channel, with the same utime, filter
  /// and state, heard once (the last kEchoSeqs seqs are remembered; an older one is not judged).
  /// A second daemon publishing the very same poses (same filter, same inputs, started together)
  /// is told by each seq then coming twice.
  bool checkEcho(const lcmloc::pose_t& m);
  int64_t foreignOutputs() const { return foreign_outputs_; }
  /// Something the operator must know (e.g. a hand-over that found nothing to start from): a
  /// warning log line and a status event at the daemon's latest time.
  void warn(const std::string& event, const std::string& detail);
  /// Processes everything still in the reorder window and publishes a final status.
  void shutdown();
  app::Heartbeat::Counters counters() const;
  /// The active filter's latest state (for checkpoints).
  core::FilterState activeState() const { return engine_->activeState(); }
  std::string activeFilter() const { return engine_->activeFilter(); }
  /// Has any input been processed since the start (or the last release)?
  int64_t processed() const { return engine_->counters().processed; }
  /// The engine's inputs later than the horizon by channel; the horizon [us]; inputs released early.
  const std::map<std::string, core::LateInputs>& lateInputs() const { return engine_->lateInputs(); }
  int64_t horizonUs() const { return engine_->horizonUs(); }
  int64_t releasedEarly() const { return engine_->counters().released_early; }
  int64_t messagesIn() const { return messages_in_; }
  int64_t rejected() const { return rejected_; }
  int64_t gaps() const { return gaps_; }
  int64_t covered() const { return covered_; }

 private:
  /// Messages of type T on channel through the intake's `take` (and undecodable ones through
  /// its decodeError), then intakeOne().
  template <typename T>
  void subscribe(const std::string& channel, void (DaemonIntake::*take)(const std::string&, const T&, IntakeItem&)) {
    bus_.subscribe<T>(
        channel,
        [this, take](const std::string& c, const T& m, int64_t recv_utime) {
          if (!timing_) return intakeOne([&](IntakeItem& item) { (intake_.*take)(c, m, item); });
          if constexpr (!std::is_same_v<T, lcmloc::fusion_control_t>) timing_->arrived(c, m.utime, recv_utime);
          const auto t0 = std::chrono::steady_clock::now();
          intakeOne([&](IntakeItem& item) { (intake_.*take)(c, m, item); });
          timing_->step(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), recv_utime);
        },
        [this](const std::string& c, const std::string& why) {
          intakeOne([&](IntakeItem& item) { intake_.decodeError(c, why, item); });
        });
  }
  /// fill(item) into the item divert() gives, or into item_ and apply() it at once.
  template <typename Fill>
  void intakeOne(Fill&& fill) {
    IntakeItem& item = slot_ ? slot_() : item_;
    fill(item);
    if (!slot_) apply(item);
  }
  /// What the sequence tracker found about a message (a gap, a restart, an ignored seq):
  /// counted, a warning and a status event.
  void reportSeq(const IntakeItem& item);
  /// A message of another publisher on its channel (IntakeItem::Kind::Held): counted as
  /// rejected; status "second_publisher" when it is the first held of that publisher, and
  /// "source_replaced" when a silent stream is replaced.
  void held(const IntakeItem& item);
  void decodeError(const std::string& ch, const std::string& why);
  void push(core::EngineInput&& in);
  /// First input after an init state (hand-over, checkpoint): more than kResumeGapUs after it
  /// is reported (status event resume_gap): the motion in between is lost.
  void checkResumeGap(const core::EngineInput& in);
  static constexpr int64_t kResumeGapUs = 100000;
  /// An input refused: counted under its channel and reason (RejectBook; "" = from why), a
  /// status event while its reason has had fewer than RejectBook::kEventsPerPeriod this period.
  void reject(const std::string& ch, int64_t seq, int64_t utime, const std::string& why, const std::string& reason = "");
  void publishState(const std::string& filter, bool active, const core::FilterState& s);
  void publishStatus(const std::string& event, const std::string& detail, int64_t utime);
  void publishControl(const core::FilterState& s);
  std::string poseChannel(const std::string& filter, bool active) const;

  const app::SystemConfig& cfg_;
  bus::MessageBus& bus_;
  std::unique_ptr<core::FusionEngine> engine_;
  /// The intake and slot_ are the replay's reading thread's, the rest its applying thread's.
  DaemonIntake intake_;
  std::function<IntakeItem&()> slot_;  ///< divert()
  IntakeItem item_;  ///< the intake's item of the message being taken in (its storage reused)
  int64_t gaps_ = 0;  ///< messages missing according to the intake's sequence checks
  std::map<std::string, int64_t> out_seq_;  ///< per output channel
  /// Per (filter, active): its POSE channel, that channel's seq counter (a node of out_seq_) and
  /// the encode buffer, reused for every state it publishes (no per-message allocations).
  struct PoseOut {
    std::string filter;
    bool active = false;
    std::string channel;
    int64_t* seq = nullptr;
    std::vector<uint8_t> bytes;  ///< bus::encodePose's output
  };
  std::vector<PoseOut> pose_out_;
  PoseOut control_out_;  ///< the control pose's (Options::control)
  /// The last kEchoSeqs POSE this daemon published on the active channel, by seq: a fingerprint
  /// of utime, filter and state, and whether it came back already.
  static constexpr int64_t kEchoSeqs = 8192;
  struct Echo {
    uint64_t fingerprint = 0;
    bool heard = false;
  };
  bool echo_ = false;  ///< Options::echo
  DaemonTiming* timing_ = nullptr;  ///< Options::timing
  std::vector<Echo> echoes_;
  int64_t pose_seqs_ = 0;  ///< seqs published on the active POSE channel (the next one's seq)
  int64_t foreign_outputs_ = 0;
  RejectBook rejects_;              ///< refused inputs per channel and reason
  app::LogThrottle log_throttle_;  ///< per kind of problem: first 5, then 1 in 1000
  int64_t messages_in_ = 0, rejected_ = 0, last_utime_ = 0, next_status_utime_ = INT64_MIN;
  int64_t status_period_us_ = 0;  ///< fusion.status_period [us]
  core::FilterStatus last_status_ = core::FilterStatus::Uninitialized;
  bool event_seen_ = false;
  bool hold_ = false;
  /// Inputs queued while holding, at most kMaxHeld (a flood while waiting for the hand-over must
  /// not take the memory): beyond, the oldest go first (they are the likeliest to be covered by
  /// the state handed over), counted in held_dropped_ and said in the "started" event.
  std::deque<core::EngineInput> held_;
  static constexpr std::size_t kMaxHeld = 200000;
  int64_t held_dropped_ = 0;
  /// Inputs at or before this (and within fusion.max_time_jump of it) were covered by the init state.
  std::optional<int64_t> init_utime_;
  bool resumed_ = false;  ///< the first input after the init state was seen (resume_gap checked)
  bool releasing_seen_ = false;  ///< release(saw_queued = true) is processing the queue
  int64_t max_jump_us_ = 0;  ///< fusion.max_time_jump
  int64_t covered_ = 0;
};

}  // namespace lcmloc::fusion
