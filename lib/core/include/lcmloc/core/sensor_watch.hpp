#pragma once
// The sensor watch: a sensor channel that stops delivering (a GNSS receiver unplugged, a camera
// pipeline hung) is said once, and once again when it comes back. Measured in message time of
// the other inputs (the newest input's utime), never the wall clock: the live daemon and the
// replay of its log say the same at the same input. Only channels with an expected period
// (SensorExpectation::period_us) are watched; nothing waits for a silent one.
#include <cstdint>
#include <map>
#include <string>

#include "lcmloc/core/engine_config.hpp"
#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/time_guard.hpp"

namespace lcmloc::core {

class SensorWatch {
 public:
  explicit SensorWatch(const std::map<std::string, SensorExpectation>& sensors);

  /// An input of channel with message time utime was taken; newest: the newest input's time now.
  /// Calls said(kind, utime, fields) for the watched channel it resumes and each one that fell
  /// silent (in channel order).
  template <typename F>
  void input(const std::string& channel, int64_t utime, int64_t newest, F&& said) {
    if (watched_.empty() || newest == INT64_MIN) return;
    if (const auto it = watched_.find(channel); it != watched_.end()) {
      Watched& w = it->second;
      if (w.stopped) {
        w.stopped = false;
        said(EventKind::SensorResumed, utime, events::SensorSilence{channel, false, w.last, utime, w.period_us, w.limit_us});
      }
      if (!w.seen || utime > w.last) w.last = utime;
      w.seen = true;
    }
    for (auto& [name, w] : watched_) {
      if (!w.seen) {  // its clock starts with the first input of any channel
        w.last = newest;
        w.seen = true;
      } else if (!w.stopped && apartBy(newest, w.last, w.limit_us)) {
        w.stopped = true;
        said(EventKind::SensorStopped, newest, events::SensorSilence{name, true, w.last, newest, w.period_us, w.limit_us});
      }
    }
  }
  /// Any channel watched.
  bool active() const { return !watched_.empty(); }
  /// A new time base: every clock starts again at the next input (nothing is said of the gap).
  void restart();
  /// Watched channels silent now.
  int stopped() const;

 private:
  struct Watched {
    int64_t period_us = 0, limit_us = 0;  ///< limit: kStopPeriods periods and the expected delay
    int64_t last = 0;
    bool seen = false, stopped = false;
  };
  std::map<std::string, Watched> watched_;
};

}  // namespace lcmloc::core
