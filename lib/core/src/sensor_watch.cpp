#include "lcmloc/core/sensor_watch.hpp"

namespace lcmloc::core {

SensorWatch::SensorWatch(const std::map<std::string, SensorExpectation>& sensors) {
  for (const auto& [channel, s] : sensors)
    if (s.period_us > 0) {
      Watched w;
      w.period_us = s.period_us;
      w.limit_us = kStopPeriods * s.period_us + s.delay_us;
      watched_.emplace(channel, w);
    }
}

void SensorWatch::restart() {
  for (auto& [name, w] : watched_) {
    w.seen = false;
    w.stopped = false;
  }
}

int SensorWatch::stopped() const {
  int n = 0;
  for (const auto& [name, w] : watched_) n += w.stopped ? 1 : 0;
  return n;
}

}  // namespace lcmloc::core
