#pragma once
// Sampling schedule of the sensor models: one tick every `period` of message time, and the
// saturating time arithmetic the models use. Middleware free.
#include <cstdint>
#include <limits>

namespace lcmloc::sim {

/// a + b, saturated to the int64 range instead of overflowing (undefined behaviour) where a
/// message time is corrupt.
inline int64_t saturatingAdd(int64_t a, int64_t b) {
  int64_t r;
  if (__builtin_add_overflow(a, b, &r))
    return b > 0 ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
  return r;
}

/// (a - b) in seconds, as a double: exact enough for any pair of message times and never an
/// integer overflow (the difference of two int64 need not fit in one).
inline double secondsBetween(int64_t a, int64_t b) {
  int64_t d;
  if (!__builtin_sub_overflow(a, b, &d)) return static_cast<double>(d) * 1e-6;
  return (static_cast<double>(a) - static_cast<double>(b)) * 1e-6;
}

/// Advances a schedule whose next tick is `next` to truth time `now`. Returns true when a sample
/// is due (now >= next); next is then the first tick after now, found in one step: stepping tick
/// by tick hung a driver for hours on one ground-truth message with a corrupt utime far ahead.
/// Time going back by more than a period (a restarted simulator, or the first sample after such
/// a corrupt message) restarts the schedule at now, so the sensor does not fall silent. Every
/// step is overflow free for any int64 now and next (the next tick saturates at INT64_MAX);
/// period < 1 counts as 1.
inline bool scheduleDue(int64_t& next, int64_t now, int64_t period) {
  if (period < 1) period = 1;
  if (now < saturatingAdd(next, -period)) next = now;
  if (now < next) return false;
  // now >= next: their difference fits in uint64 (the wrap-around of the unsigned subtraction
  // is exact). The first tick after now is now + (period - (now - next) % period), which is
  // next + k period as before, computed without forming (now - next) in int64.
  const auto rem = static_cast<int64_t>((static_cast<uint64_t>(now) - static_cast<uint64_t>(next)) %
                                        static_cast<uint64_t>(period));
  next = saturatingAdd(now, period - rem);
  return true;
}

}  // namespace lcmloc::sim
