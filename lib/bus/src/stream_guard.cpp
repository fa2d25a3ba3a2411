#include "lcmloc/bus/stream_guard.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "lcmloc/core/time_guard.hpp"

namespace lcmloc::bus {
namespace {

/// seq goes on from last: the same, or at most kMaxAhead after it (any two int64 seqs, a corrupt
/// one included, compared without overflow).
bool goesOn(int64_t last, int64_t seq) {
  return seq == last || (seq > last && !core::apartBy(seq, last, StreamGuard::kMaxAhead));
}

/// A message more than kMaxStepUs after its stream's last time does not move the stream's time:
/// one message with a huge time would otherwise make the stream span kSilenceUs at once (and
/// replace the established stream with its next kReplaceAfter messages).
constexpr int64_t kMaxStepUs = 5 * StreamGuard::kSilenceUs;

bool fromStart(int64_t seq) { return seq >= 0 && seq <= StreamGuard::kMaxAhead; }

void add(int64_t seq, int64_t utime, int64_t& last_seq, int64_t& last_utime) {
  last_seq = std::max(last_seq, seq);
  if (!core::apartBy(utime, last_utime, kMaxStepUs)) last_utime = std::max(last_utime, utime);
}

}  // namespace

std::string StreamVerdict::describe(const std::string& channel) const {
  if (kind == Kind::Replaced && lone)
    return fmt::format("{}: a stream (first seq {} at utime {}) replaces the lone message the channel began with (seq {} "
                       "at utime {})",
                       channel, first_seq, first_utime, established_seq, established_utime);
  if (kind == Kind::Replaced)
    return fmt::format("{}: a new stream (first seq {} at utime {}) replaces the one silent since seq {} at utime {}",
                       channel, first_seq, first_utime, established_seq, established_utime);
  return fmt::format("{}: a second publisher (first seq {} at utime {}) beside the established one (last seq {} at "
                     "utime {}): its messages are held apart",
                     channel, first_seq, first_utime, established_seq, established_utime);
}

StreamVerdict StreamGuard::observe(const std::string& channel, int64_t seq, int64_t utime) {
  StreamVerdict v;
  auto [it, added] = channels_.try_emplace(channel);
  Channel& c = it->second;
  if (added) {
    c.est = Stream{seq, utime, seq, utime, 1, fromStart(seq)};
    return v;
  }
  v.established_seq = c.est.last_seq;
  v.established_utime = c.est.last_utime;
  if (goesOn(c.est.last_seq, seq)) {
    add(seq, utime, c.est.last_seq, c.est.last_utime);
    ++c.est.count;
    if (c.has_other) {
      ++c.est_since_other;
      c.other_mark = c.other.last_utime;
      c.other_since_mark = 0;
    }
    return v;
  }
  if (c.has_other && goesOn(c.other.last_seq, seq)) {
    add(seq, utime, c.other.last_seq, c.other.last_utime);
    ++c.other.count;
    v.first_seq = c.other.first_seq;
    v.first_utime = c.other.first_utime;
    ++c.other_since_mark;
    const bool est_silent = c.other_since_mark >= kReplaceAfter &&
                            core::apartBy(c.other.last_utime, c.other_mark, kSilenceUs - 1);
    if (!c.est.confirmed() || (c.other.from_start && est_silent)) {  // the established one is gone, or was never one
      v.lone = !c.est.confirmed();
      c.est = c.other;
      c.has_other = false;
      c.reported = false;
      v.kind = StreamVerdict::Kind::Replaced;
      return v;
    }
    if (c.other.from_start && c.est_since_other == 0) return v;  // silent since the other began: a restart, so far
    v.kind = StreamVerdict::Kind::Held;
    ++held_;
    if (!c.reported) {
      c.reported = true;
      v.detected = true;
      ++detections_;
    }
    return v;
  }
  // Neither: another stream begins (or a lone corrupt seq, which looks the same until the next).
  if (!c.has_other || c.other.count > 1) c.reported = false;
  c.other = Stream{seq, utime, seq, utime, 1, fromStart(seq)};
  c.has_other = true;
  c.est_since_other = 0;
  c.other_mark = utime;
  c.other_since_mark = 0;
  return v;
}

}  // namespace lcmloc::bus
