#include "lcmloc/core/odometry_gaps.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "lcmloc/core/time_guard.hpp"

namespace lcmloc::core {

OdometryGaps::OdometryGaps(const OdometryGapConfig& cfg, FilterBank& bank, OutputDecimation& decimation,
                           const EngineOutputs& out)
    : cfg_(cfg), bank_(bank), decimation_(decimation), out_(out) {
  if (!(cfg.max_gap_us >= 0) || !(std::isfinite(cfg.accel_std) && cfg.accel_std >= 0) ||
      !(std::isfinite(cfg.yaw_rate_std) && cfg.yaw_rate_std >= 0))
    throw std::invalid_argument("odometry gap: max_gap, accel_std and yaw_rate_std must be >= 0");
}

int64_t OdometryGaps::Track::period() const {
  double sum_dt = 0;
  for (int k = 0; k < n; ++k) sum_dt += dt[k];
  return n > 0 ? static_cast<int64_t>(sum_dt / n * 1e6) : 0;
}

bool OdometryGaps::odometryMissing(int64_t utime) const {
  const int64_t limit = cfg_.max_gap_us;
  return limit > 0 && last_odometry_utime_ != INT64_MIN &&
         apartBy(utime, last_odometry_utime_, std::max(limit, 2 * newest_track_->period()));
}

void OdometryGaps::odometry(const EngineInput& in, const OdometryInput& odo) {
  if (auto gap = detect(in, odo)) bridge(std::move(*gap));
}

std::optional<events::GapBridged> OdometryGaps::detect(const EngineInput& in, const OdometryInput& odo) {
  auto [it, first] = tracks_.try_emplace(in.channel);
  Track& t = it->second;
  if (odo.utime >= last_odometry_utime_) {
    last_odometry_utime_ = odo.utime;
    newest_track_ = &t;
  }
  const int64_t prev_utime = t.utime, prev_seq = t.seq;
  t.utime = odo.utime;
  t.seq = in.seq;
  if (first) return resume_from_ != INT64_MIN ? resumeGap(in, odo) : std::nullopt;
  if (odo.utime <= prev_utime) return std::nullopt;
  const bool follows = in.seq == prev_seq + 1;
  if (cfg_.max_gap_us <= 0 || follows || !apartBy(odo.utime, prev_utime, cfg_.max_gap_us)) {
    const int i = t.next;
    t.dt[i] = static_cast<double>(odo.utime - prev_utime) * 1e-6;
    t.ds[i] = odo.delta_s;
    t.dth[i] = odo.delta_theta;
    t.steer[i] = odo.steering;
    t.next = i + 1 == Track::kRecent ? 0 : i + 1;
    if (t.n < Track::kRecent) ++t.n;
    return std::nullopt;
  }
  return gapAfter(in, odo, t, prev_utime, prev_seq);
}

/// odo comes after a gap in its channel t (the previous input at prev_utime, prev_seq): bridged
/// at the recent speed, yaw rate and steering of the channel.
events::GapBridged OdometryGaps::gapAfter(const EngineInput& in, const OdometryInput& odo, Track& t,
                                          int64_t prev_utime, int64_t prev_seq) const {
  events::GapBridged e;
  e.input = refOf(in);
  e.previous_seq = prev_seq;
  e.max_gap_us = cfg_.max_gap_us;
  OdometryGap& gap = e.gap;
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
  t.n = t.next = 0;  // (the increment after the gap says nothing about the speed over its interval)
  return e;
}

/// The first odometry input after initialize(): more than max_odometry_gap after the state (a
/// daemon started again from its checkpoint after a crash, the motion of its down time unseen)
/// it is a gap, bridged at the speed of this first increment over the sender's period.
std::optional<events::GapBridged> OdometryGaps::resumeGap(const EngineInput& in, const OdometryInput& odo) {
  const int64_t from = resume_from_, limit = cfg_.max_gap_us;
  resume_from_ = INT64_MIN;
  if (limit <= 0 || !apartBy(odo.utime, from, limit)) return std::nullopt;
  const int64_t period = cfg_.resume_period_us;
  events::GapBridged e;
  e.input = refOf(in);
  e.resume = true;
  e.max_gap_us = limit;
  e.period_us = period;
  OdometryGap& gap = e.gap;
  gap.from_utime = from;
  gap.next_utime = odo.utime;
  gap.to_utime = std::max(from, odo.utime - period);
  gap.seconds = static_cast<double>(gap.to_utime - gap.from_utime) * 1e-6;
  gap.speed = period > 0 ? odo.delta_s / (static_cast<double>(period) * 1e-6) : 0.0;
  gap.yaw_rate = period > 0 ? odo.delta_theta / (static_cast<double>(period) * 1e-6) : 0.0;
  gap.has_steering = odo.has_steering;
  gap.steering = odo.steering;
  return e;
}

/// Every filter bridges the gap (before the increment after it), and the event says so.
void OdometryGaps::bridge(events::GapBridged&& e) {
  e.gap.accel_std = cfg_.accel_std;
  e.gap.yaw_rate_std = cfg_.yaw_rate_std;
  e.gap.max_position_std = bank_.activeConfig().lockout_max_std;
  decimation_.applyAccumulated();  // the bridge starts where the odometry before it ended
  bank_.forEach([&](Filter& f, bool) { e.bridged.push_back(f.bridgeOdometryGap(e.gap)); });
  after_gap_ = true;
  spread_ = 3.0 * positionSigma(bank_.active().state());
  const int64_t utime = e.gap.next_utime;
  out_.event(EventKind::OdometryGap, utime, std::move(e));
}

void OdometryGaps::resumeFrom(int64_t utime) {
  tracks_.clear();  // (their next input is the first after the state)
  newest_track_ = nullptr;
  last_odometry_utime_ = INT64_MIN;
  resume_from_ = utime;
}

void OdometryGaps::reset() {
  resumeFrom(INT64_MIN);
  after_gap_ = false;
  spread_ = 0.0;
}

}  // namespace lcmloc::core
