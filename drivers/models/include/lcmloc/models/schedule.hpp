#pragma once
// Sampling schedule of the sensor models: one tick every `period` of message time. Middleware free.
#include <cstdint>
#include <limits>

namespace lcmloc::models {

/// Advances a schedule whose next tick is `next` to truth time `now`. Returns true when a sample
/// is due (now >= next); next is then the first tick after now, found in one step: stepping tick
/// by tick hung a driver for hours on one ground-truth message with a corrupt utime far ahead.
/// Time going back by more than a period (a restarted simulator, or the first sample after such
/// a corrupt message) restarts the schedule at now, so the sensor does not fall silent.
inline bool scheduleDue(int64_t& next, int64_t now, int64_t period) {
  if (now < next - period) next = now;
  if (now < next) return false;
  const int64_t steps = (now - next) / period + 1;
  next = steps > (std::numeric_limits<int64_t>::max() - next) / period ? std::numeric_limits<int64_t>::max()
                                                                        : next + steps * period;
  return true;
}

}  // namespace lcmloc::models
