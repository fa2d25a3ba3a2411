// The words of the engine's events: the detail of each FUSION_STATUS message. Byte for byte
// what the replay goldens hold (tests/data/golden): a change here changes every output log.
#include <cstdio>
#include <string>
#include <type_traits>

#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/time_guard.hpp"

namespace lcmloc::core {
namespace {

using std::to_string;

/// "CHANNEL seq N"
std::string at(const InputRef& in) { return in.channel + " seq " + to_string(in.seq); }
/// "CHANNEL seq N utime T"
std::string atTime(const InputRef& in) { return at(in) + " utime " + to_string(in.utime); }

std::string text(const events::Late& e) {
  if (e.duplicate) return atTime(e.input) + ": duplicate";
  std::string s = atTime(e.input) + ": older than already processed utime " + to_string(e.processed_utime);
  if (e.newest == INT64_MIN || e.newest < e.input.utime) return s;
  char t[200];
  std::snprintf(t, sizeof t, " (%.3f s behind it); it came %.3f s after its time (the newest input: utime %lld), "
                "the horizon is %.3f s", secondsBetween(e.processed_utime, e.input.utime),
                secondsBetween(e.newest, e.input.utime), static_cast<long long>(e.newest),
                static_cast<double>(e.horizon_us) * 1e-6);
  return s + t;
}

std::string text(const events::ReleasedEarly& e) {
  char t[300];
  std::snprintf(t, sizeof t, ": released before its time: the horizon (%.3f s) holds at most %zu inputs "
                "(fusion.max_queued); %lld released early so far", static_cast<double>(e.horizon_us) * 1e-6,
                e.max_queued, static_cast<long long>(e.early));
  return atTime(e.input) + t;
}

std::string text(const events::SensorSilence& e) {
  char t[300];
  if (e.stopped)
    std::snprintf(t, sizeof t, ": no input since utime %lld, %.3f s of message time before the newest input (utime "
                  "%lld), more than %.3f s (its period %.3f s)", static_cast<long long>(e.last_utime),
                  secondsBetween(e.newest, e.last_utime), static_cast<long long>(e.newest),
                  static_cast<double>(e.limit_us) * 1e-6, static_cast<double>(e.period_us) * 1e-6);
  else
    std::snprintf(t, sizeof t, ": input again at utime %lld after none since utime %lld",
                  static_cast<long long>(e.newest), static_cast<long long>(e.last_utime));
  return e.channel + t;
}

std::string text(const events::Outlier& e) {
  const InputRef& s = e.input;
  std::string missing;
  if (e.ahead && e.odometry_utime != INT64_MIN) {
    char t[200];
    std::snprintf(t, sizeof t, "; no odometry for %.3f s before it (the last at utime %lld): the odometry is "
                  "missing, nothing places this input", static_cast<double>(s.utime - e.odometry_utime) * 1e-6,
                  static_cast<long long>(e.odometry_utime));
    missing = t;
  }
  return atTime(s) + ": " + to_string(e.ahead ? secondsApart(s.utime, e.newest) : secondsApart(e.newest, s.utime)) +
         (e.ahead ? " s ahead of" : " s behind") + " the newest input (utime " + to_string(e.newest) +
         "), not followed by its time base" + missing;
}

std::string text(const events::CommandAhead& e) {
  return atTime(e.input) + ": a command " + to_string(secondsApart(e.input.utime, e.newest)) +
         " s ahead of the newest input (utime " + to_string(e.newest) + "), more than fusion.max_time_jump";
}

std::string text(const events::TimeJump& e) {
  const std::string head = at(e.first) + ": ";
  const std::string n = "confirmed by the inputs of " + to_string(e.confirm_span_us / 1000) + " ms in a row";
  if (!e.back)
    return head + "new time base: utime " + to_string(e.first.utime) + " after " + to_string(e.newest) + ", " + n;
  return head + "time went back " + to_string(secondsApart(e.newest, e.first.utime)) + " s (utime " +
         to_string(e.first.utime) + " after " + to_string(e.newest) + ", " + n + "): the sources started over; " +
         e.restarted + " restarted from the configured initial state";
}

std::string text(const events::Lockout& e) { return e.filter + ": consecutive gate rejections, covariance inflated"; }

std::string text(const events::Recovered& e) {
  return e.filter + (e.after_gap ? ": measurement accepted again after the odometry gap" : ": measurement accepted again");
}

std::string text(const events::Ambiguous& e) {
  char t[400];
  std::snprintf(t, sizeof t,
                "%s: the marker taken after the odometry gap may be a neighbour of the one passed: the "
                "position was known to %.2f m (3 sigma) before it, more than half the marker spacing "
                "(%.2f m), and the markers are alike; confirm the pose (lcmloc-ctl set-pose, a fix)",
                e.filter.c_str(), e.spread, e.spacing);
  return t;
}

std::string text(const events::Restarted& e) {
  if (e.cause.empty()) return e.filter + ": its state became non-finite: started from its configured initial state";
  return e.filter + ": " + e.cause + ": started from its configured initial state, then " + e.then_applied + " applied";
}

std::string text(const events::NonFinite& e) { return at(e.input) + ": non-finite " + e.what; }

std::string text(const events::FixNotMade& e) { return at(e.input) + ": landmark fix refused: " + e.why; }

std::string text(const events::FixGated& e) {
  char why[160];
  std::snprintf(why, sizeof why, "landmark fix refused by %s's gate (Mahalanobis distance %.1f > %.1f, %d in a row)",
                e.filter.c_str(), e.distance, e.gate, e.in_a_row);
  return at(e.input) + ": " + why;
}

std::string text(const events::FixLockout& e) {
  return at(e.input) + ": " + e.filter + " takes the landmark fix after " + to_string(e.after) + " refused in a row";
}

std::string text(const events::Fix& e) {
  char detail[200];
  std::snprintf(detail, sizeof detail,
                "landmark fix (x %.3f, y %.3f, theta %.6f), moved by (%.3f, %.3f, %.6f), condition %.1f", e.pose[0],
                e.pose[1], e.pose[2], e.moved[0], e.moved[1], e.moved[2], e.condition);
  return at(e.input) + ": " + detail;
}

std::string text(const events::ImuSaturated& e) {
  char detail[200];
  std::snprintf(detail, sizeof detail,
                ": forward acceleration %.2f m/s^2 at or beyond gnss.accel_saturation %.2f m/s^2: not used "
                "by %s (%lld samples so far)",
                e.accel, e.limit, e.filter.c_str(), static_cast<long long>(e.samples));
  return at(e.input) + detail;
}

std::string text(const events::GapBridged& e) {
  const OdometryGap& g = e.gap;
  char head[300];
  if (e.resume)
    std::snprintf(head, sizeof head,
                  "%s seq %lld: %.3f s of message time without odometry since the state the filters started from "
                  "(utime %lld to %lld; a daemon started again after a crash?); bridged at %.2f m/s (its first "
                  "increment over %.3f s)",
                  e.input.channel.c_str(), static_cast<long long>(e.input.seq), g.seconds,
                  static_cast<long long>(g.from_utime), static_cast<long long>(g.to_utime), g.speed,
                  static_cast<double>(e.period_us) * 1e-6);
  else
    std::snprintf(head, sizeof head,
                  "%s seq %lld after seq %lld: %.3f s of message time without odometry (utime %lld to %lld, "
                  "max_odometry_gap %.3f s), %s; bridged at %.2f m/s",
                  e.input.channel.c_str(), static_cast<long long>(e.input.seq),
                  static_cast<long long>(e.previous_seq), g.seconds, static_cast<long long>(g.from_utime),
                  static_cast<long long>(g.to_utime), static_cast<double>(e.max_gap_us) * 1e-6,
                  e.input.seq > e.previous_seq ? "messages lost" : "the sender started over", g.speed);
  std::string detail = head;
  for (const auto& b : e.bridged) detail += "; " + b;
  return detail;
}

std::string text(const events::Relocalized& e) {
  const Relocalization& r = e.evidence;
  char t[400];
  if (r.from_landmarks) {
    std::snprintf(t, sizeof t,
                  "%s re-localized: %d observations of %d landmarks agree within %.2f m (placed by the dead-reckoned "
                  "motion; the first at utime %lld) and disagree with the estimate: position moved %.2f m, heading "
                  "changed by %.4f rad (1 sigma %.4f rad)",
                  e.filter.c_str(), r.fixes, r.landmarks, r.spread, static_cast<long long>(r.first_utime), r.jump,
                  r.heading_change, r.heading_std);
    return at(e.input) + ": " + t;
  }
  std::snprintf(t, sizeof t,
                "%s re-localized: %d GPS fixes agree within %.2f m (carried forward by the dead-reckoned motion; "
                "the first at utime %lld) and disagree with the estimate: position moved %.2f m to the newest fix, ",
                e.filter.c_str(), r.fixes, r.spread, static_cast<long long>(r.first_utime), r.jump);
  char h[160];
  if (r.heading_from_chord)
    std::snprintf(h, sizeof h, "heading from their chord (changed by %.4f rad, 1 sigma %.4f rad)", r.heading_change,
                  r.heading_std);
  else
    std::snprintf(h, sizeof h, "heading kept (1 sigma opened to %.4f rad)", r.heading_std);
  return at(e.input) + ": " + t + h;
}

std::string text(const events::Answer& e, bool ack) {
  using C = events::Answer::Command;
  const std::string head = at(e.command) + ": ";
  switch (e.what) {
    case C::Switch:
      if (!ack) return head + "switch to '" + e.filter + "': " + e.why;
      return head + "switched " + e.previous + " -> " + e.filter +
             (e.why.empty() ? std::string() : " (" + e.why + ": started from its configured initial state)");
    case C::Reset: return head + "reset " + e.filter;
    case C::SetPose: return head + "set_pose" + (ack ? std::string() : ": " + e.why);
  }
  return head;
}

}  // namespace

const char* eventName(EventKind kind) {
  switch (kind) {
    case EventKind::Ack: return "ack";
    case EventKind::Refused: return "refused";
    case EventKind::Lockout: return "lockout";
    case EventKind::Recovered: return "recovered";
    case EventKind::Ambiguous: return "ambiguous";
    case EventKind::Restarted: return "restarted";
    case EventKind::TooOld: return "too_old";
    case EventKind::TooNew: return "too_new";
    case EventKind::TimeJump: return "time_jump";
    case EventKind::BadInput: return "bad_input";
    case EventKind::OdometryGap: return "odometry_gap";
    case EventKind::ImuSaturated: return "imu_saturated";
    case EventKind::Fix: return "fix";
    case EventKind::FixRefused: return "fix_refused";
    case EventKind::FixLockout: return "fix_lockout";
    case EventKind::Relocalized: return "relocalized";
    case EventKind::HorizonFull: return "horizon_full";
    case EventKind::SensorStopped: return "sensor_stopped";
    case EventKind::SensorResumed: return "sensor_resumed";
  }
  return "event";
}

std::string eventText(const EngineEvent& e) {
  return std::visit(
      [&e](const auto& f) {
        if constexpr (std::is_same_v<std::decay_t<decltype(f)>, events::Answer>)
          return text(f, e.kind == EventKind::Ack);
        else
          return text(f);
      },
      e.fields);
}

}  // namespace lcmloc::core
