#pragma once
// The fusion daemon's wall-clock timing (FUSION_TIMING, fusion_timing_t): per input channel the
// delay of its messages (arrival wall time minus message time), the age of its last message and
// its rate; per message the processing time through the daemon. Kept beside the estimate, never
// fed into it: the engine sees message times only, and POSE is the same with or without this.
// Live only (lcmloc-fusion); the offline replay has no arrival times to measure.
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "lcmloc/core/engine_config.hpp"
#include "lcmloc/fusion_timing_t.hpp"

namespace lcmloc::fusion {

class DaemonTiming {
 public:
  /// window_us: [us, wall] span of the figures (samples older are dropped).
  explicit DaemonTiming(int64_t window_us = 5000000) : window_us_(window_us) {}
  /// A message of channel with message time msg_utime arrived at recv_utime (wall, us).
  void arrived(const std::string& channel, int64_t msg_utime, int64_t recv_utime);
  /// One message went through the daemon in `seconds` (wall), finished at now_us.
  void step(double seconds, int64_t now_us);
  /// The figures at wall time now_us (seq left to the publisher), with the engine's count of
  /// inputs later than the horizon by channel (message time).
  lcmloc::fusion_timing_t report(int64_t now_us, const std::map<std::string, core::LateInputs>& late = {});

 private:
  struct Sample {
    int64_t at;    ///< [us, wall]
    double value;  ///< delay or processing time [s]
  };
  struct Channel {
    std::deque<Sample> delays;
    int64_t first = 0;  ///< [us, wall] first arrival (a channel younger than the window: its rate over its age)
    int64_t last = 0;   ///< [us, wall] last arrival
  };
  void expire(std::deque<Sample>& d, int64_t now_us) const;
  int64_t window_us_;
  std::map<std::string, Channel> channels_;
  std::deque<Sample> steps_;
  static constexpr std::size_t kMaxSamples = 100000;  ///< per deque: a flood keeps the memory bounded
};

/// The value at fraction q (0..1) of values (nearest rank; reorders values); 0 when empty.
double quantile(std::vector<double>& values, double q);

}  // namespace lcmloc::fusion
