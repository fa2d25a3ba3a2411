#include "lcmloc/core/engine.hpp"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "filter_internal.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/chi2.hpp"
#include "lcmloc/core/text.hpp"

namespace lcmloc::core {
namespace {

/// FNV-1a: a hash that is the same on every run and machine (std::hash is not guaranteed to be).
uint32_t stableHash(const std::string& s) {
  uint32_t h = 2166136261u;
  for (unsigned char c : s) h = (h ^ c) * 16777619u;
  return h;
}

int typeRank(const EngineInput& in) {
  switch (in.payload.index()) {
    case 2: return 0;  // control
    case 0: return 1;  // odometry
    case 1: return 2;  // ruler
    case 3: return 3;  // imu
    case 4: return 4;  // gps
    case 5: return 5;  // landmark
    case 6: return 6;  // beacon
    default: return 7; // bearings
  }
}

bool isFinite(const OdometryInput& o) {
  return std::isfinite(o.delta_s) && std::isfinite(o.steering) && std::isfinite(o.delta_theta);
}
bool isFinite(const ImuInput& m) {
  return m.accel.allFinite() && m.gyro.allFinite() && m.mag.allFinite();
}
/// A fix without a fix carries no position: it is handed on (the filter reports "no_fix").
bool isFinite(const GpsInput& g) {
  return !g.has_fix || (std::isfinite(g.x) && std::isfinite(g.y));
}
bool isFinite(const LandmarkObservation& m) {
  return std::isfinite(m.range) && std::isfinite(m.bearing) && std::isfinite(m.range_std) &&
         std::isfinite(m.bearing_std);
}
bool isFinite(const BeaconRange& m) { return std::isfinite(m.range) && std::isfinite(m.range_std); }

}  // namespace

struct FusionEngine::Impl {
  EngineConfig cfg;
  MarkerMap map;
  EngineOutputs out;
  ReorderBuffer<EngineInput> buffer;
  FilterConfig active_cfg;
  std::unique_ptr<Filter> active;
  std::vector<std::unique_ptr<Filter>> shadows;
  FilterStatus last_status = FilterStatus::Ok;
  Counters counters;

  Impl(EngineConfig c, MarkerMap m, EngineOutputs o)
      : cfg(std::move(c)), map(std::move(m)), out(std::move(o)), buffer(cfg.reorder_window_us),
        active_cfg(cfg.filter) {
    const LandmarkFixGate& g = cfg.fix_gate;
    if (!(g.probability >= 0.0 && g.probability < 1.0) || g.lockout_rejections < 0)
      throw std::invalid_argument("fix gate: probability must be in [0, 1) and lockout_rejections >= 0");
    if (g.probability > 0.0) fix_gate = chi2Quantile(g.probability, 3);
    const OdometryGapConfig& og = cfg.odometry_gap;
    if (!(og.max_gap_us >= 0) || !(std::isfinite(og.accel_std) && og.accel_std >= 0) ||
        !(std::isfinite(og.yaw_rate_std) && og.yaw_rate_std >= 0))
      throw std::invalid_argument("odometry gap: max_gap, accel_std and yaw_rate_std must be >= 0");
    active = makeFilter(active_cfg, map);
    last_status = active->state().status;
    for (const auto& type : cfg.shadow) {
      FilterConfig sc = cfg.filter;
      sc.type = type;
      shadows.push_back(makeFilter(sc, map));
    }
  }

  void event(const std::string& name, const std::string& detail, int64_t utime) const {
    if (out.on_event) out.on_event(name, detail, utime);
  }

  TimeBaseGuard<EngineInput> guard{cfg.max_time_jump_us};  ///< EngineConfig::max_time_jump_us

  /// Why an input ahead was not placed when the odometry stopped before it: a measurement needs
  /// the odometry up to its time, and none came (the odometry source is missing, not this one).
  std::string missingOdometry(const EngineInput& s, bool ahead) const {
    if (!ahead || std::holds_alternative<OdometryInput>(s.payload) || last_odometry_utime == INT64_MIN ||
        !apartBy(s.utime, last_odometry_utime, cfg.max_time_jump_us))
      return "";
    char text[200];
    std::snprintf(text, sizeof text, "; no odometry for %.3f s before it (the last at utime %lld): the odometry is "
                  "missing, nothing places this input", static_cast<double>(s.utime - last_odometry_utime) * 1e-6,
                  static_cast<long long>(last_odometry_utime));
    return text;
  }

  /// A held input the old time base went on after: an outlier.
  void dropHeld(const EngineInput& s, int side, int64_t newest) {
    const bool ahead = side > 0;
    ++(ahead ? counters.too_new : counters.too_old);
    event(ahead ? "too_new" : "too_old",
          s.channel + " seq " + std::to_string(s.seq) + " utime " + std::to_string(s.utime) + ": " +
              std::to_string(ahead ? secondsApart(s.utime, newest) : secondsApart(newest, s.utime)) +
              (ahead ? " s ahead of" : " s behind") + " the newest input (utime " + std::to_string(newest) +
              "), not followed by its time base" + missingOdometry(s, ahead),
          s.utime);
  }

  /// A new time base. Ahead: its inputs are taken in order. Behind: the sources started over (a
  /// restarted simulator, a log played again): what is queued of the old base is processed, then
  /// the filters start afresh as in a newly started daemon (the active filter type kept), so the
  /// second run gives what the first gave.
  void newTimeBase(int side, const EngineInput& first, int64_t newest) {
    const std::string at = first.channel + " seq " + std::to_string(first.seq) + ": ";
    const std::string n = "confirmed by the inputs of " + std::to_string(guard.confirmSpan() / 1000) + " ms in a row";
    if (side > 0) {
      event("time_jump",
            at + "new time base: utime " + std::to_string(first.utime) + " after " + std::to_string(newest) + ", " + n,
            first.utime);
      return;
    }
    buffer.flush([this](const OrderKey&, const EngineInput& e) { process(e); });
    if (unpublished) publishAll();
    active = makeFilter(active_cfg, map);
    for (auto& s : shadows) {
      FilterConfig sc = cfg.filter;
      sc.type = s->name();
      s = makeFilter(sc, map);
    }
    last_status = active->state().status;
    buffer = ReorderBuffer<EngineInput>(cfg.reorder_window_us);
    odometry_since_output = 0;
    accumulated = unpublished = imu_saturating = false;
    imu_saturated = 0;
    refused_fixes.clear();
    odometry_tracks.clear();
    last_odometry_utime = INT64_MIN;
    newest_track = cached_track = nullptr;
    resume_from = INT64_MIN;
    after_gap = false;
    event("time_jump",
          at + "time went back " + std::to_string(secondsApart(newest, first.utime)) + " s (utime " +
              std::to_string(first.utime) + " after " + std::to_string(newest) + ", " + n +
              "): the sources started over; " + active->name() + " restarted from the configured initial state",
          first.utime);
  }

  /// The reorder window refused in (key): older than what was processed, or a duplicate.
  [[gnu::cold, gnu::noinline]] void tooOld(const EngineInput& in, const OrderKey& key) {
    ++counters.too_old;
    std::string detail = in.channel + " seq " + std::to_string(in.seq) + " utime " + std::to_string(in.utime);
    if (buffer.contains(key))
      detail += ": duplicate";
    else
      detail += ": older than already processed utime " + std::to_string(buffer.lastReleased().utime);
    event("too_old", detail, in.utime);
  }

  /// orderKey() with the channel hash of the previous input reused when the channel is the same.
  ChannelName hashed_channel;
  uint32_t channel_hash = stableHash("");
  OrderKey orderKey(const EngineInput& in) {
    if (in.channel != hashed_channel) {
      hashed_channel = in.channel;
      channel_hash = stableHash(in.channel);
    }
    return OrderKey{in.utime, typeRank(in) * 1024 + static_cast<int>(channel_hash % 1024), in.seq};
  }

  FilterState scratch;  ///< reused for every published state (no allocations per message)
  void emitState(Filter& f, bool is_active) {
    if (is_active) unpublished = false;  // output_every > 1: the active state is out
    if (!out.on_state) return;
    f.stateInto(scratch);
    if (!scratch.x.allFinite() || !scratch.P.allFinite()) {
      // Never on the bus: a filter whose numbers ran away starts over, and says so.
      startFresh(f, configOf(f, is_active), scratch.utime);
      event("restarted", f.name() + ": its state became non-finite: started from its configured initial state",
            scratch.utime);
      f.stateInto(scratch);
    }
    out.on_state(f.name(), is_active, scratch);
  }

  template <typename F>
  void forEachFilter(F&& f) {
    f(*active, true);
    for (auto& s : shadows) f(*s, false);
  }

  void process(const EngineInput& in) {
    ++counters.processed;
    const bool odometry = std::holds_alternative<OdometryInput>(in.payload);
    if (cfg.output_every > 1 && !odometry) applyAccumulated();  // measurements see all odometry
    std::visit([&](const auto& p) { handle(in, p); }, in.payload);
    const FilterStatus now = active->status();
    if (now != last_status) statusChanged(in, now);
    if (now == FilterStatus::Ok) after_gap = false;
    last_status = now;
  }
  /// The active filter's status went from last_status to now with input in: an event when it
  /// entered or left a lock-out, or recovered after an odometry gap.
  [[gnu::noinline]] void statusChanged(const EngineInput& in, FilterStatus now) {
    if (now == FilterStatus::Lockout)
      event("lockout", active->name() + ": consecutive gate rejections, covariance inflated",
            in.utime);
    else if (last_status == FilterStatus::Lockout)
      event("recovered", active->name() + ": measurement accepted again", in.utime);
    else if (after_gap && now == FilterStatus::Ok) {
      event("recovered", active->name() + ": measurement accepted again after the odometry gap", in.utime);
      if (active->uses(Measurement::Ruler) && gap_spread > 0.5 * marker_spacing) {
        char text[400];
        std::snprintf(text, sizeof text,
                      "%s: the marker taken after the odometry gap may be a neighbour of the one passed: the "
                      "position was known to %.2f m (3 sigma) before it, more than half the marker spacing "
                      "(%.2f m), and the markers are alike; confirm the pose (lcmloc-ctl set-pose, a fix)",
                      active->name().c_str(), gap_spread, marker_spacing);
        event("ambiguous", text, in.utime);
      }
    }
  }

  /// An input with a NaN or Inf field (skipped): event bad_input.
  [[gnu::cold, gnu::noinline]] void badInput(const EngineInput& in, const char* what) {
    event("bad_input", in.channel + " seq " + std::to_string(in.seq) + ": non-finite " + what, in.utime);
  }

  void handle(const EngineInput& in, const OdometryInput& odo) {
    if (!isFinite(odo)) return badInput(in, "odometry");
    odometryGap(in, odo);
    if (cfg.output_every > 1) return handleBatched(odo);
    forEachFilter([&](Filter& f, bool is_active) {
      f.predict(odo);
      emitState(f, is_active);
    });
  }

  /// Odometry gaps (EngineConfig::odometry_gap): per odometry channel, the last input and the
  /// recent increments (speed, yaw rate, steering, period before a gap).
  struct OdometryTrack {
    int64_t utime = 0, seq = 0;
    static constexpr int kRecent = 10;
    std::array<double, kRecent> dt{}, ds{}, dth{}, steer{};
    int n = 0, next = 0;
    bool has_steering = false;
    void clearRecent() { n = next = 0; }
    /// [us] The recent period (0: not known).
    int64_t period() const {
      double sum_dt = 0;
      for (int k = 0; k < n; ++k) sum_dt += dt[k];
      return n > 0 ? static_cast<int64_t>(sum_dt / n * 1e6) : 0;
    }
  };
  std::map<std::string, OdometryTrack> odometry_tracks;  ///< (nodes stay put: pointers below)
  int64_t last_odometry_utime = INT64_MIN;  ///< newest odometry input on any channel
  const OdometryTrack* newest_track = nullptr;  ///< the channel of that input
  /// The track of the previous odometry input's channel (one lookup per channel change, not per
  /// message: this runs for every odometry message).
  OdometryTrack* cached_track = nullptr;
  ChannelName cached_track_channel;
  /// A measurement at utime has no odometry to place it: the newest odometry input is older by
  /// more than max_odometry_gap and twice its channel's period (a slow sender is not missing).
  bool odometryMissing(int64_t utime) const {
    const int64_t limit = cfg.odometry_gap.max_gap_us;
    return limit > 0 && last_odometry_utime != INT64_MIN &&
           apartBy(utime, last_odometry_utime, std::max(limit, 2 * newest_track->period()));
  }
  bool after_gap = false;  ///< an odometry gap was bridged; no measurement accepted since
  void odometryGap(const EngineInput& in, const OdometryInput& odo) {
    const OdometryGapConfig& gc = cfg.odometry_gap;
    bool first = false;
    if (!cached_track || in.channel != cached_track_channel) first = findTrack(in.channel);
    OdometryTrack& t = *cached_track;
    if (odo.utime >= last_odometry_utime) {
      last_odometry_utime = odo.utime;
      newest_track = &t;
    }
    const int64_t prev_utime = t.utime, prev_seq = t.seq;
    t.utime = odo.utime;
    t.seq = in.seq;
    t.has_steering = odo.has_steering;
    if (first) {
      if (resume_from != INT64_MIN) resumeGap(in, odo);
      return;
    }
    if (odo.utime <= prev_utime) return;
    const bool follows = in.seq == prev_seq + 1;
    if (gc.max_gap_us <= 0 || follows || !apartBy(odo.utime, prev_utime, gc.max_gap_us)) {
      const int i = t.next;
      t.dt[i] = static_cast<double>(odo.utime - prev_utime) * 1e-6;
      t.ds[i] = odo.delta_s;
      t.dth[i] = odo.delta_theta;
      t.steer[i] = odo.steering;
      t.next = i + 1 == OdometryTrack::kRecent ? 0 : i + 1;
      if (t.n < OdometryTrack::kRecent) ++t.n;
      return;
    }
    gapFound(in, odo, t, prev_utime, prev_seq);
  }
  /// The track of channel into cached_track (a new one when the channel is new: returns true).
  [[gnu::noinline]] bool findTrack(const ChannelName& channel) {
    auto [it, inserted] = odometry_tracks.try_emplace(channel);
    cached_track = &it->second;
    cached_track_channel = channel;
    return inserted;
  }
  /// odo comes after a gap in its channel t (the previous input at prev_utime, prev_seq).
  [[gnu::cold, gnu::noinline]] void gapFound(const EngineInput& in, const OdometryInput& odo, OdometryTrack& t,
                                             int64_t prev_utime, int64_t prev_seq) {
    const OdometryGapConfig& gc = cfg.odometry_gap;
    OdometryGap gap;
    double sum_dt = 0, sum_ds = 0, sum_dth = 0, sum_steer = 0;
    for (int k = 0; k < t.n; ++k) {
      sum_dt += t.dt[k];
      sum_ds += t.ds[k];
      sum_dth += t.dth[k];
      sum_steer += t.steer[k];
    }
    // The increment after the gap covers its own period only: the channel's recent period.
    const int64_t period = t.n > 0 ? static_cast<int64_t>(std::llround(sum_dt / t.n * 1e6)) : 0;
    gap.from_utime = prev_utime;
    gap.next_utime = odo.utime;
    gap.to_utime = std::max(prev_utime, odo.utime - period);
    gap.seconds = static_cast<double>(gap.to_utime - gap.from_utime) * 1e-6;
    gap.speed = sum_dt > 0 ? sum_ds / sum_dt : 0.0;
    gap.yaw_rate = sum_dt > 0 ? sum_dth / sum_dt : 0.0;
    gap.has_steering = odo.has_steering;
    gap.steering = t.n > 0 ? sum_steer / t.n : odo.steering;
    t.clearRecent();  // (the increment after the gap says nothing about the speed over its interval)
    char head[300];
    std::snprintf(head, sizeof head,
                  "%s seq %lld after seq %lld: %.3f s of message time without odometry (utime %lld to %lld, "
                  "max_odometry_gap %.3f s), %s; bridged at %.2f m/s",
                  in.channel.c_str(), static_cast<long long>(in.seq), static_cast<long long>(prev_seq),
                  gap.seconds, static_cast<long long>(gap.from_utime), static_cast<long long>(gap.to_utime),
                  static_cast<double>(gc.max_gap_us) * 1e-6,
                  in.seq > prev_seq ? "messages lost" : "the sender started over", gap.speed);
    bridge(gap, head, odo.utime);
  }

  /// Every filter bridges the gap (before the increment after it), and the event says so.
  void bridge(OdometryGap& gap, const std::string& head, int64_t utime) {
    gap.accel_std = cfg.odometry_gap.accel_std;
    gap.yaw_rate_std = cfg.odometry_gap.yaw_rate_std;
    gap.max_position_std = active_cfg.lockout_max_std;
    if (cfg.output_every > 1) applyAccumulated();  // the bridge starts where the odometry before it ended
    std::string detail = head;
    forEachFilter([&](Filter& f, bool) { detail += "; " + f.bridgeOdometryGap(gap); });
    after_gap = true;
    gap_spread = 3.0 * positionSigma(active->state());
    event("odometry_gap", detail, utime);
  }
  /// [m] 3 sigma of the active filter's position after the last bridged gap (the larger axis).
  double gap_spread = 0.0;
  /// [m] The smallest distance between two markers of the map (+inf: fewer than two): after a
  /// gap whose spread exceeds half of it, the marker taken may be a neighbour ("ambiguous").
  double marker_spacing = closestMarkers(map);
  static double closestMarkers(const MarkerMap& m) {
    std::vector<Marker> v(m);
    std::sort(v.begin(), v.end(), [](const Marker& a, const Marker& b) { return a.x < b.x; });
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < v.size(); ++i)
      for (std::size_t j = i + 1; j < v.size() && v[j].x - v[i].x < best; ++j)
        best = std::min(best, std::hypot(v[j].x - v[i].x, v[j].y - v[i].y));
    return best;
  }

  /// The time of the state initialize() started the filters from, until the first odometry input.
  int64_t resume_from = INT64_MIN;
  /// The first odometry input after initialize(): more than max_odometry_gap after the state
  /// (a daemon started again from its checkpoint after a crash, the motion of its down time
  /// unseen) it is a gap, bridged at the speed of this first increment over the sender's period.
  void resumeGap(const EngineInput& in, const OdometryInput& odo) {
    const int64_t from = resume_from, limit = cfg.odometry_gap.max_gap_us;
    resume_from = INT64_MIN;
    if (limit <= 0 || !apartBy(odo.utime, from, limit)) return;
    const int64_t period = cfg.odometry_gap.resume_period_us;
    OdometryGap gap;
    gap.from_utime = from;
    gap.next_utime = odo.utime;
    gap.to_utime = std::max(from, odo.utime - period);
    gap.seconds = static_cast<double>(gap.to_utime - gap.from_utime) * 1e-6;
    gap.speed = period > 0 ? odo.delta_s / (static_cast<double>(period) * 1e-6) : 0.0;
    gap.yaw_rate = period > 0 ? odo.delta_theta / (static_cast<double>(period) * 1e-6) : 0.0;
    gap.has_steering = odo.has_steering;
    gap.steering = odo.steering;
    char head[300];
    std::snprintf(head, sizeof head,
                  "%s seq %lld: %.3f s of message time without odometry since the state the filters started from "
                  "(utime %lld to %lld; a daemon started again after a crash?); bridged at %.2f m/s (its first "
                  "increment over %.3f s)",
                  in.channel.c_str(), static_cast<long long>(in.seq), gap.seconds,
                  static_cast<long long>(gap.from_utime), static_cast<long long>(gap.to_utime), gap.speed,
                  static_cast<double>(period) * 1e-6);
    bridge(gap, head, odo.utime);
  }

  // Output decimation with batched time update (EngineConfig::output_every > 1).
  int odometry_since_output = 0;  ///< odometry messages since the last regular output
  bool accumulated = false;       ///< some filter holds composed odometry not yet applied
  bool unpublished = false;       ///< odometry processed whose state was not published yet
  void applyAccumulated() {
    if (!accumulated) return;
    forEachFilter([](Filter& f, bool) { f.applyAccumulated(); });
    accumulated = false;
  }
  void handleBatched(const OdometryInput& odo) {
    forEachFilter([&](Filter& f, bool) {
      if (f.accumulate(odo))
        accumulated = true;
      else
        f.predict(odo);
    });
    unpublished = true;
    if (++odometry_since_output < cfg.output_every) return;
    odometry_since_output = 0;
    publishAll();
  }
  void publishAll() {
    applyAccumulated();
    forEachFilter([&](Filter& f, bool is_active) { emitState(f, is_active); });
    unpublished = false;
  }

  void handle(const EngineInput&, const RulerDetection& det) {
    const bool unplaced = odometryMissing(det.utime);
    forEachFilter([&](Filter& f, bool is_active) {
      if (!f.uses(Measurement::Ruler)) return;
      GateDecision d;
      if (unplaced) {  // the filter's pose is of the last odometry, not of this detection
        d = detail::decision(det.utime, det.sensor, det.seq, std::numeric_limits<double>::infinity());
        d.reason = "no_odometry";
      } else {
        d = f.update(det);
      }
      if (is_active) ++(d.accepted ? counters.accepted : counters.rejected);
      if (out.on_decision) out.on_decision(f.name(), is_active, d);
      emitState(f, is_active);
    });
  }

  /// IMU samples and GPS fixes: only filters that use them see them; a decision (and the
  /// state after it) is published only when the filter used the measurement.
  template <typename M>
  void handleAbsolute(const EngineInput& in, const M& m, Measurement kind, const char* what) {
    if (!isFinite(m)) return badInput(in, what);
    forEachFilter([&](Filter& f, bool is_active) {
      if (!f.uses(kind)) return;
      const std::optional<GateDecision> d = f.update(m);
      if (!d) return;
      if (is_active) ++(d->accepted ? counters.accepted : counters.rejected);
      if (out.on_decision) out.on_decision(f.name(), is_active, *d);
      emitState(f, is_active);
    });
  }
  /// Saturated IMU samples of the active filter so far, and whether the last sample was one.
  int64_t imu_saturated = 0;
  bool imu_saturating = false;
  void handle(const EngineInput& in, const ImuInput& m) {
    handleAbsolute(in, m, Measurement::Imu, "IMU sample");
    // One event per saturated stretch (a pothole gives a few samples in a row), not per sample.
    const int64_t n = active->saturatedImuSamples();
    const bool saturated = n > imu_saturated;
    if (saturated && !imu_saturating) {
      char detail[200];
      std::snprintf(detail, sizeof detail,
                    ": forward acceleration %.2f m/s^2 at or beyond gnss.accel_saturation %.2f m/s^2: not used "
                    "by %s (%lld samples so far)",
                    m.accel[0], active_cfg.gnss.accel_saturation, active->name().c_str(), static_cast<long long>(n));
      event("imu_saturated", in.channel + " seq " + std::to_string(in.seq) + detail, in.utime);
    }
    imu_saturating = saturated;
    imu_saturated = n;  // a switched-to filter counts from 0
  }
  void handle(const EngineInput& in, const GpsInput& m) {
    handleAbsolute(in, m, Measurement::Gps, "GPS fix");
  }

  void handle(const EngineInput& in, const LandmarkObservation& m) {
    handleAbsolute(in, m, Measurement::Landmark, "landmark observation");
  }
  void handle(const EngineInput& in, const BeaconRange& m) {
    handleAbsolute(in, m, Measurement::Beacon, "beacon range");
  }
  void handle(const EngineInput& in, const BearingsInput& b) { landmarkFix(in, b); }

  /// A boxed input: as the input itself (but a command, below).
  template <typename T>
  void handle(const EngineInput& in, const Boxed<T>& boxed) {
    handle(in, *boxed);
  }
  void handle(const EngineInput& in, const Boxed<ControlCommand>& cmd) {
    command = in.channel + " seq " + std::to_string(in.seq) + ": ";
    std::visit([&](const auto& c) { control(in.utime, c); }, *cmd);
  }
  /// "CHANNEL seq N: " of the command being applied: its answer ("ack", "refused") names it, so
  /// that a sender tells its own answer from that of another command at the same time.
  std::string command;
  void answer(const std::string& name, const std::string& detail, int64_t utime) const {
    event(name, command + detail, utime);
  }

  void control(int64_t utime, const SwitchFilter& c) {
    std::unique_ptr<Filter> next;
    try {
      next = makeFilter(c.config, map);
    } catch (const std::invalid_argument& e) {
      answer("refused", std::string("switch to '") + c.config.type + "': " + e.what(), utime);
      return;
    }
    FilterState from = active->state();
    from.utime = std::max(from.utime, utime);
    std::string note;
    try {
      next->initialize(from);
    } catch (const std::exception& e) {  // a state that cannot be carried over (not finite)
      startFresh(*next, c.config, from.utime);
      note = std::string(" (") + e.what() + ": started from its configured initial state)";
    }
    const std::string old = active->name();
    active = std::move(next);
    active_cfg = c.config;
    refused_fixes.erase(filterKey(*active, true));
    answer("ack", "switched " + old + " -> " + active->name() + note, utime);
  }

  /// The configuration a running filter was made from.
  FilterConfig configOf(const Filter& f, bool is_active) const {
    if (is_active) return active_cfg;
    FilterConfig sc = cfg.filter;
    sc.type = f.name();
    return sc;
  }
  /// Starts f again from its configured initial state at utime.
  void startFresh(Filter& f, const FilterConfig& fc, int64_t utime) {
    auto n = makeFilter(fc, map);
    FilterState s = n->state();
    s.utime = utime;
    f.initialize(s);
  }
  /// Applies a pose fix; a filter whose other states cannot be carried over (not finite) starts
  /// from its configured initial state first, so a fix or set_pose also repairs a broken filter.
  bool applyFixTo(Filter& f, bool is_active, const PoseFix& fix) {
    try {
      return f.applyFix(fix);
    } catch (const std::exception& e) {
      startFresh(f, configOf(f, is_active), fix.utime);
      event("restarted", f.name() + ": " + e.what() + ": started from its configured initial state, then " +
                             fix.source + " applied", fix.utime);
      return f.applyFix(fix);
    }
  }

  void control(int64_t utime, const ResetFilter&) {
    forEachFilter([&](Filter& f, bool is_active) { startFresh(f, configOf(f, is_active), utime); });
    refused_fixes.clear();
    answer("ack", "reset " + active->name(), utime);
  }

  void landmarkFix(const EngineInput& in, const BearingsInput& b);
  /// Consecutive landmark fixes each filter's gate refused (EngineConfig::fix_gate), by
  /// filterKey; cleared when the filters start over.
  std::map<std::string, int> refused_fixes;
  /// The fix gate's threshold: chi-square (3 dof) at EngineConfig::fix_gate.probability; +inf = none.
  double fix_gate = std::numeric_limits<double>::infinity();
  static std::string filterKey(const Filter& f, bool is_active) { return (is_active ? "active " : "shadow ") + f.name(); }

  void control(int64_t utime, const SetPose& c) {
    // A pose fix for every filter: each moves what depends on the pose with it (odo_ins turns
    // its velocity with the heading). Checked as the variances it gives: a standard deviation
    // of 1e200 squares to infinity, one of 1e-200 to 0.
    PoseFix fix;
    fix.utime = utime;
    fix.pose = c.pose;
    fix.cov = c.stddev.array().square().matrix().asDiagonal();
    fix.source = "set_pose";
    if (!(c.stddev.array() > 0).all()) return answer("refused", "set_pose: stddev must be > 0", utime);
    if (const std::string why = detail::fixProblem(fix); !why.empty())
      return answer("refused", "set_pose: " + why + " (pose and stddev must be finite, stddev > 0)", utime);
    std::string not_taken;
    forEachFilter([&](Filter& f, bool is_active) {
      if (!applyFixTo(f, is_active, fix)) not_taken += (not_taken.empty() ? "" : ", ") + f.name();
    });
    refused_fixes.clear();
    if (!not_taken.empty()) return answer("refused", "set_pose: not taken by " + not_taken, utime);
    answer("ack", "set_pose", utime);
  }
};

void FusionEngine::Impl::landmarkFix(const EngineInput& in, const BearingsInput& b) {
  GateDecision d = detail::decision(in.utime, b.sensor.empty() ? in.channel.str() : b.sensor, in.seq,
                                    std::numeric_limits<double>::infinity());
  auto refuse = [&](const std::string& reason, const std::string& ev, const std::string& why) {
    d.reason = reason;
    if (out.on_decision) out.on_decision(active->name(), true, d);
    ++counters.rejected;
    event(ev, in.channel + " seq " + std::to_string(in.seq) + ": landmark fix refused: " + why, in.utime);
  };
  if (b.ids.size() != b.bearings.size())
    return refuse("bad_input", "bad_input", "ids and bearings differ in count");
  for (double a : b.bearings)
    if (!std::isfinite(a)) return refuse("bad_input", "bad_input", "non-finite bearing");
  for (int id : b.ids)
    if (!cfg.landmarks.count(id))
      return refuse("bad_input", "bad_input", "landmark " + std::to_string(id) + " not in the map");
  if (b.ids.size() < 3) {
    // Fewer than three landmarks in view is a normal reading (the vehicle is away from them):
    // a decision that says so, no event.
    d.reason = "too_few_landmarks";
    if (out.on_decision) out.on_decision(active->name(), true, d);
    return;
  }
  if (b.ids.size() != 3) return refuse("bad_input", "bad_input", "need exactly three bearings");
  const FilterState prior = active->state();
  if (!prior.x.head<3>().allFinite()) return refuse("bad_input", "bad_input", "filter pose not finite");
  // Bearings CCW from the body x (forward) axis -> clockwise from the body axis (landmark_fix);
  // theta CCW from east -> heading clockwise from north.
  std::vector<landmark::Bearing> bs;
  for (std::size_t i = 0; i < b.ids.size(); ++i) bs.push_back({b.ids[i], -b.bearings[i]});
  landmark::FixOptions o = cfg.fix;
  if (std::isfinite(b.bearing_std) && b.bearing_std > 0) o.sigma_bearing = b.bearing_std;
  const double psi_prior = wrapAngle(M_PI / 2 - prior.x[2]);
  const landmark::FixResult r =
      landmark::leastSquaresFix(cfg.landmarks, bs, prior.x.head<2>(), psi_prior, o);
  if (!r.ok) return refuse("geometry", "fix_refused", r.error);
  PoseFix fix;
  fix.utime = in.utime;
  fix.pose = Vec3(r.position.x(), r.position.y(), wrapAngle(M_PI / 2 - r.heading));
  Mat3 J = Mat3::Identity();
  J(2, 2) = -1.0;
  fix.cov = J * r.covariance * J.transpose();
  fix.source = in.channel;
  d.gate = fix_gate;
  const std::string at = in.channel + " seq " + std::to_string(in.seq) + ": ";
  bool active_took_it = false;
  forEachFilter([&](Filter& f, bool is_active) {
    GateDecision fd = d;
    const FilterState s = is_active ? prior : f.state();
    Vec3 v = fix.pose - s.x.head<3>();
    v[2] = wrapAngle(v[2]);
    const Mat3 S = s.P.topLeftCorner<3, 3>() + fix.cov;
    fd.innovation = v;
    fd.mahalanobis = v.dot(S.ldlt().solve(v));
    int& refused = refused_fixes[filterKey(f, is_active)];
    // A NaN distance (a broken state) is not outside: the fix repairs the filter (applyFixTo).
    const bool outside = fd.mahalanobis > fix_gate;
    const bool lockout = outside && cfg.fix_gate.lockout_rejections > 0 && refused >= cfg.fix_gate.lockout_rejections;
    if (outside && !lockout) {
      ++refused;
      fd.reason = "gate";
      if (is_active) ++counters.rejected;
      if (out.on_decision) out.on_decision(f.name(), is_active, fd);
      char why[160];
      std::snprintf(why, sizeof why, "landmark fix refused by %s's gate (Mahalanobis distance %.1f > %.1f, %d in a row)",
                    f.name().c_str(), fd.mahalanobis, fix_gate, refused);
      event("fix_refused", at + why, in.utime);
      return;
    }
    fd.reason = lockout ? "fix_lockout" : "fix";
    fd.accepted = applyFixTo(f, is_active, fix);
    if (!fd.accepted) fd.reason = "bad_input";
    if (fd.accepted) refused = 0;
    if (is_active) active_took_it = fd.accepted;
    if (is_active) ++(fd.accepted ? counters.accepted : counters.rejected);
    if (out.on_decision) out.on_decision(f.name(), is_active, fd);
    emitState(f, is_active);
    if (lockout && fd.accepted) event("fix_lockout", at + f.name() + " takes the landmark fix after " +
                                      std::to_string(cfg.fix_gate.lockout_rejections) + " refused in a row", in.utime);
  });
  if (!active_took_it) return;  // (the shadows' decisions are on GATE)
  d.innovation = fix.pose - prior.x.head<3>();
  d.innovation[2] = wrapAngle(d.innovation[2]);
  char detail[200];
  std::snprintf(detail, sizeof detail,
                "landmark fix (x %.3f, y %.3f, theta %.6f), moved by (%.3f, %.3f, %.6f), condition %.1f",
                fix.pose[0], fix.pose[1], fix.pose[2], d.innovation[0], d.innovation[1], d.innovation[2],
                r.condition);
  event("fix", at + detail, in.utime);
}

FusionEngine::FusionEngine(EngineConfig cfg, MarkerMap map, EngineOutputs out)
    : impl_(std::make_unique<Impl>(std::move(cfg), std::move(map), std::move(out))) {}

FusionEngine::~FusionEngine() = default;
FusionEngine::FusionEngine(FusionEngine&&) noexcept = default;
FusionEngine& FusionEngine::operator=(FusionEngine&&) noexcept = default;

bool FusionEngine::push(EngineInput&& in) {
  Impl& m = *impl_;
  const int64_t utime = in.utime;
  if (std::holds_alternative<Boxed<ControlCommand>>(in.payload)) return pushCommand(std::move(in));
  return m.guard.offer(
      std::move(in), utime, [this](EngineInput&& e) { return take(std::move(e)); },
      [&m](const EngineInput& s, int side, int64_t newest) { m.dropHeld(s, side, newest); },
      [&m](int side, const EngineInput& first, int64_t newest) { m.newTimeBase(side, first, newest); });
}

bool FusionEngine::pushCommand(EngineInput&& in) {
  // A command waits for the sensors' time, it never makes it: it neither releases the inputs
  // before it nor takes part in the time-jump guard (commands sent at once by several tools
  // each one reorder window after the newest answer would otherwise carry the time ahead of the
  // sensors, whose inputs then came too late). One beyond the guard would wait for a time that
  // may never come: refused.
  Impl& m = *impl_;
  const int64_t utime = in.utime;
  const int64_t newest = m.guard.newest(), jump = m.cfg.max_time_jump_us;
  if (jump > 0 && newest != INT64_MIN && apartBy(utime, newest, jump)) {
    ++m.counters.too_new;
    m.event("too_new",
            in.channel + " seq " + std::to_string(in.seq) + " utime " + std::to_string(utime) + ": a command " +
                std::to_string(secondsApart(utime, newest)) + " s ahead of the newest input (utime " +
                std::to_string(newest) + "), more than fusion.max_time_jump",
            utime);
    return false;
  }
  return take(std::move(in), false);
}

bool FusionEngine::take(EngineInput&& in, bool advance) {
  const OrderKey key = impl_->orderKey(in);
  if (!impl_->buffer.push(key, std::move(in), advance)) {  // refused: `in` is untouched
    impl_->tooOld(in, key);
    return false;
  }
  if (!advance) return true;
  impl_->guard.took(key.utime);
  impl_->buffer.releaseReady([this](const OrderKey&, const EngineInput& e) { impl_->process(e); });
  return true;
}

void FusionEngine::flush() {
  impl_->guard.flush([this](const EngineInput& s, int side, int64_t newest) {  // never confirmed
    impl_->dropHeld(s, side, newest);
  });
  impl_->buffer.flush([this](const OrderKey&, const EngineInput& e) { impl_->process(e); });
  if (impl_->unpublished) impl_->publishAll();  // output_every > 1: the state after the last input
}

void FusionEngine::initialize(const FilterState& state) {
  impl_->forEachFilter([&](Filter& f, bool) { f.initialize(state); });
  impl_->odometry_tracks.clear();  // (their next input is the first after the state)
  impl_->newest_track = impl_->cached_track = nullptr;
  impl_->last_odometry_utime = INT64_MIN;
  impl_->resume_from = state.utime;
  impl_->last_status = impl_->active->state().status;
}

std::string FusionEngine::activeFilter() const { return impl_->active->name(); }
FilterState FusionEngine::activeState() const { return impl_->active->state(); }
FusionEngine::Counters FusionEngine::counters() const { return impl_->counters; }

}  // namespace lcmloc::core
