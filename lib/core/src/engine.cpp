#include "lcmloc/core/engine.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <vector>

#include "filter_internal.hpp"
#include "lcmloc/core/commands.hpp"
#include "lcmloc/core/control_pose.hpp"
#include "lcmloc/core/filter_bank.hpp"
#include "lcmloc/core/fix_stage.hpp"
#include "lcmloc/core/input_order.hpp"
#include "lcmloc/core/odometry_gaps.hpp"
#include "lcmloc/core/output_decimation.hpp"
#include "lcmloc/core/sensor_watch.hpp"

namespace lcmloc::core {
namespace {

/// Saturated IMU samples of the active filter: one event per saturated stretch (a pothole gives
/// a few samples in a row), not per sample.
class ImuSaturationWatch {
 public:
  /// After the filters took an IMU sample: whether a saturated stretch began (n: the active
  /// filter's saturated samples so far; a switched-to filter counts from 0).
  bool began(int64_t n) {
    const bool saturated = n > counted_;
    const bool began = saturated && !saturating_;
    saturating_ = saturated;
    counted_ = n;
    return began;
  }
  void reset() {
    counted_ = 0;
    saturating_ = false;
  }

 private:
  int64_t counted_ = 0;
  bool saturating_ = false;
};

}  // namespace

struct FusionEngine::Impl final : InputOrder::Client {
  EngineConfig cfg;
  SharedMapIndex map;
  EngineOutputs out;
  EngineCounters counters;
  FilterBank bank;
  OutputDecimation decimation;
  OdometryGaps gaps;
  LandmarkFixStage fixes;
  Commands commands;
  ImuSaturationWatch imu;
  InputOrder order;
  SensorWatch watch;
  std::map<std::string, LateInputs> late_inputs;  ///< by channel
  bool horizon_full = false;  ///< released early since the horizon last had room (one event per stretch)
  ControlPredictor control;
  std::vector<ControlPredictor::Waiting> waiting;  ///< emitControl's (storage reused)
  /// [m] The smallest distance between two markers of the map (+inf: fewer than two): after a
  /// gap whose spread exceeds half of it, the marker taken may be a neighbour ("ambiguous").
  const double marker_spacing;
  FilterStatus last_status;  ///< the active filter's status after the input before

  Impl(EngineConfig c, MarkerMap m, EngineOutputs o)
      : cfg(std::move(c)), map(std::make_shared<const MapIndex>(std::move(m))), out(std::move(o)), bank(cfg.filter, cfg.shadow, map, out),
        decimation(cfg.output_every, bank), gaps(cfg.odometry_gap, bank, decimation, out),
        fixes(cfg, bank, out, counters), commands(bank, fixes, out),
        order(cfg.horizonUs(), cfg.max_time_jump_us, cfg.max_queued, *this), watch(cfg.sensors), control(map), marker_spacing(map->closestPair()),
        last_status(bank.active().state().status) {}

  /// Every part starts afresh (a new time base; the active filter's type is kept).
  void reset() {
    order.reset();
    watch.restart();
    horizon_full = false;
    gaps.reset();
    bank.reset();
    decimation.reset();
    fixes.reset();
    commands.reset();
    imu.reset();
    control.invalidate();
    last_status = bank.active().state().status;
  }

  /// The control pose now (EngineOutputs::on_control): the active state and the motion inputs
  /// waiting in the reorder window.
  void emitControl() {
    waiting.clear();
    order.forEachQueued([this](const OrderKey& key, const EngineInput& e) {
      if (std::holds_alternative<OdometryInput>(e.payload) || std::holds_alternative<ImuInput>(e.payload))
        waiting.push_back({key, &e});
    });
    // Every change of the canonical state comes with a processed input, but for those below
    // (flush, initialize, reset), which start the control pose afresh.
    out.on_control(control.pose(bank.active(), bank.activeConfig(), counters.processed, waiting));
  }

  // InputOrder::Client
  void process(const EngineInput& in) override {
    ++counters.processed;
    const bool odometry = std::holds_alternative<OdometryInput>(in.payload);
    if (decimation.batching() && !odometry) decimation.applyAccumulated();  // measurements see all odometry
    std::visit([&](const auto& p) { handle(in, p); }, in.payload);
    const FilterStatus now = bank.active().status();
    if (now != last_status) statusChanged(in, now);
    if (now == FilterStatus::Ok) gaps.accepted();
    last_status = now;
  }
  /// The odometry, the measurements some filter (active or shadow) uses, and bearings when the
  /// configuration has landmarks to make a fix from move the horizon on; any other input does not
  /// (a stream on a channel the filters ignore, with its time a little ahead of the sensors',
  /// would otherwise release the canonical poses in bursts).
  bool carriesTime(const EngineInput& in) const override {
    return std::visit(
        [&](const auto& p) {
          using T = std::decay_t<decltype(p)>;
          if constexpr (detail::IsMeasurement<T>::value) {
            bool used = false;
            bank.forEach([&](const Filter& f, bool) { used = used || f.uses(InputKind<T>::measurement); });
            return used;
          } else if constexpr (std::is_same_v<T, BearingsInput>) {
            return fixes.usable();
          } else {
            return true;
          }
        },
        in.payload);
  }
  void late(const EngineInput& in, bool duplicate, int64_t processed_utime) override {
    ++counters.too_old;
    const int64_t newest = order.newest();
    if (!duplicate && newest != INT64_MIN && newest >= in.utime) {
      LateInputs& l = late_inputs[in.channel];
      ++l.count;
      l.max_lateness_us = std::max(l.max_lateness_us, timeApart(newest, in.utime));
    }
    out.event(EventKind::TooOld, in.utime, events::Late{refOf(in), duplicate, processed_utime, newest, order.window()});
  }
  void releasedEarly(const EngineInput& in) override {
    ++counters.released_early;
    if (horizon_full) return;
    horizon_full = true;
    out.event(EventKind::HorizonFull, in.utime,
              events::ReleasedEarly{refOf(in), order.maxQueued(), order.window(), counters.released_early});
  }
  /// After an input was taken: the horizon has room again (at most half full): the next early
  /// release is said again; the sensor watch sees it.
  void taken(bool watched, const std::string& channel, int64_t utime) {
    if (horizon_full && order.queued() <= order.maxQueued() / 2) horizon_full = false;
    if (!watched) return;
    watch.input(channel, utime, order.newest(),
                [this](EventKind kind, int64_t utime, events::SensorSilence s) { out.event(kind, utime, std::move(s)); });
  }
  void outlier(const EngineInput& in, bool ahead, int64_t newest) override {
    ++(ahead ? counters.too_new : counters.too_old);
    // Ahead, when the odometry stopped before it: a measurement needs the odometry up to its
    // time, and none came (the odometry source is missing, not this one).
    const int64_t last_odometry = gaps.lastOdometryUtime();
    const bool missing = ahead && !std::holds_alternative<OdometryInput>(in.payload) && last_odometry != INT64_MIN &&
                         apartBy(in.utime, last_odometry, cfg.max_time_jump_us);
    out.event(ahead ? EventKind::TooNew : EventKind::TooOld, in.utime,
              events::Outlier{refOf(in), ahead, newest, missing ? last_odometry : INT64_MIN});
  }
  void commandAhead(const EngineInput& in, int64_t newest) override {
    ++counters.too_new;
    out.event(EventKind::TooNew, in.utime, events::CommandAhead{refOf(in), newest});
  }
  /// Ahead: the new time base's inputs are taken in order. Behind: the sources started over (a
  /// restarted simulator, a log played again): what was queued of the old base is processed, then
  /// every part starts afresh as in a newly started daemon, so the second run gives what the
  /// first gave.
  void timeJumped(const EngineInput& first, int64_t newest, bool back) override {
    events::TimeJump e{refOf(first), newest, order.confirmSpan(), back, {}};
    if (back) {
      decimation.publishPending();
      reset();
      e.restarted = bank.active().name();
    } else {
      watch.restart();  // the silence before a time base ahead is not the sensors'
    }
    out.event(EventKind::TimeJump, first.utime, std::move(e));
  }

  /// The active filter's status went from last_status to now with input in: an event when it
  /// entered or left a lock-out, or recovered after an odometry gap.
  void statusChanged(const EngineInput& in, FilterStatus now) {
    const std::string& name = bank.active().name();
    if (now == FilterStatus::Lockout) {
      out.event(EventKind::Lockout, in.utime, events::Lockout{name});
    } else if (last_status == FilterStatus::Lockout) {
      out.event(EventKind::Recovered, in.utime, events::Recovered{name, false});
    } else if (gaps.afterGap() && now == FilterStatus::Ok) {
      out.event(EventKind::Recovered, in.utime, events::Recovered{name, true});
      if (bank.active().uses(Measurement::Ruler) && gaps.spread() > 0.5 * marker_spacing)
        out.event(EventKind::Ambiguous, in.utime, events::Ambiguous{name, gaps.spread(), marker_spacing});
    }
  }

  /// An input with a NaN or Inf field (skipped).
  void badInput(const EngineInput& in, const char* what) {
    out.event(EventKind::BadInput, in.utime, events::NonFinite{refOf(in), what});
  }

  void handle(const EngineInput& in, const OdometryInput& odo) {
    if (!odo.finite()) return badInput(in, "odometry");
    gaps.odometry(in, odo);
    if (decimation.batching()) return decimation.odometry(odo);
    bank.forEach([&](Filter& f, bool is_active) {
      f.predict(odo);
      bank.emitState(f, is_active);
    });
  }

  void handle(const EngineInput&, const RulerDetection& det) {
    const bool unplaced = gaps.odometryMissing(det.utime);
    bank.forEach([&](Filter& f, bool is_active) {
      if (!f.uses(Measurement::Ruler)) return;
      GateDecision d;
      if (unplaced) {  // the filter's pose is of the last odometry, not of this detection
        d = detail::decision(det.utime, det.sensor, det.seq, std::numeric_limits<double>::infinity());
        d.reason = "no_odometry";
      } else {
        d = f.update(det);
      }
      if (is_active) ++(d.accepted ? counters.accepted : counters.rejected);
      out.decision(f.name(), is_active, d);
      bank.emitState(f, is_active);
    });
  }

  /// A measurement with no special handling here (GPS fixes, landmark observations, beacon
  /// ranges, and IMU samples before their saturation watch): only filters that use its kind
  /// (InputKind<M>::measurement) see it; a decision (and the state after it) is published only
  /// when the filter used it.
  template <typename M>
  void handle(const EngineInput& in, const M& m) {
    if (!m.finite()) return badInput(in, InputKind<M>::what);
    bank.forEach([&](Filter& f, bool is_active) {
      if (!f.uses(InputKind<M>::measurement)) return;
      const std::optional<GateDecision> d = f.update(m);
      if (!d) return;
      if (is_active) ++(d->accepted ? counters.accepted : counters.rejected);
      out.decision(f.name(), is_active, *d);
      bank.emitState(f, is_active);
      if (const std::optional<Relocalization> r = f.takeRelocalization(); r && is_active)
        out.event(EventKind::Relocalized, in.utime, events::Relocalized{refOf(in), f.name(), *r});
    });
  }
  void handle(const EngineInput& in, const ImuInput& m) {
    handle<ImuInput>(in, m);
    const Filter& active = bank.active();
    const int64_t n = active.saturatedImuSamples();
    if (imu.began(n))
      out.event(EventKind::ImuSaturated, in.utime,
                events::ImuSaturated{refOf(in), m.accel[0], bank.activeConfig().gnss.accel_saturation, active.name(), n});
  }
  void handle(const EngineInput& in, const BearingsInput& b) { fixes.process(in, b); }
  void handle(const EngineInput& in, const ControlCommand& c) {
    commands.apply(in, c);
    control.invalidate();  // a switch may keep the type and change the parameters
  }
};

FusionEngine::FusionEngine(EngineConfig cfg, MarkerMap map, EngineOutputs out)
    : impl_(std::make_unique<Impl>(std::move(cfg), std::move(map), std::move(out))) {}

FusionEngine::~FusionEngine() = default;
FusionEngine::FusionEngine(FusionEngine&&) noexcept = default;
FusionEngine& FusionEngine::operator=(FusionEngine&&) noexcept = default;

bool FusionEngine::push(EngineInput&& in) {
  // An IMU sample moves the control pose only when a filter uses it (composed by the active one,
  // or moving the horizon: carriesTime); with none it would publish the control pose before it
  // again, at the IMU's rate.
  const bool motion = impl_->out.on_control && (std::holds_alternative<OdometryInput>(in.payload) ||
                                                (std::holds_alternative<ImuInput>(in.payload) &&
                                                 impl_->carriesTime(in)));
  // (what the sensor watch needs of it: the input is moved into the window)
  const bool watched = impl_->watch.active() && !std::holds_alternative<ControlCommand>(in.payload);
  const int64_t utime = in.utime;
  std::string channel;
  if (watched) channel = in.channel;
  const bool taken = impl_->order.push(std::move(in));
  if (taken) impl_->taken(watched, channel, utime);
  if (taken && motion) impl_->emitControl();
  return taken;
}

void FusionEngine::flush() {
  impl_->order.flush();
  impl_->decimation.publishPending();  // output_every > 1: the state after the last input
  impl_->control.invalidate();
}

void FusionEngine::initialize(const FilterState& state) {
  impl_->bank.initialize(state);
  impl_->control.invalidate();
  impl_->gaps.resumeFrom(state.utime);
  impl_->last_status = impl_->bank.active().state().status;
}

std::string FusionEngine::activeFilter() const { return impl_->bank.active().name(); }
FilterState FusionEngine::activeState() const { return impl_->bank.active().state(); }
FusionEngine::Counters FusionEngine::counters() const { return impl_->counters; }
const std::map<std::string, LateInputs>& FusionEngine::lateInputs() const { return impl_->late_inputs; }
int64_t FusionEngine::horizonUs() const { return impl_->order.window(); }

}  // namespace lcmloc::core
