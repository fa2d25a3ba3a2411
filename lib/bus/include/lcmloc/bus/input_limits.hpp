#pragma once
// Physical limits on what the fusion takes (fusion.limits): a message that decodes, and whose
// every field is finite and in its type's range, may still describe a motion no vehicle makes:
// a second stream of odometry, a flipped byte, a driver with the wrong unit. The check uses the
// interval since the channel's previous message taken, so it keeps a little state per channel;
// it runs in the daemon's intake on the arrival order, as the replay runs it.
#include <cstdint>
#include <string>
#include <unordered_map>

#include "lcmloc/core/engine_input.hpp"

namespace lcmloc::bus {

struct InputLimits {
  double max_speed = 70.0;      ///< [m/s] the speed an odometry increment implies over its interval; 0 = off
  /// [rad/s] the yaw rate an odometry heading increment implies; 0 = off. A small robot spins at
  /// 6-8 rad/s (a differential drive of 0.4 m/s wheels 0.1 m apart), a car turns at 1.
  double max_yaw_rate = 12.0;
  double max_steering = 0.8;    ///< [rad] |steering angle| of car-like odometry; 0 = off
  /// [m] the ruler's span: |lateral offset| of a detection at most this (the filter's
  /// ruler_half_width with a margin, set by the config reader); 0 = off
  double max_lateral_offset = 0.0;
  /// GPS: a fix further from the channel's previous fix taken than max_speed times the interval
  /// plus this many sigma (the fixes' own, or gps_std) of the difference is refused; 0 = off
  double max_fix_jump_sigma = 10.0;
  double gps_std = 2.9;         ///< [m] a fix's sigma when it carries none (the filter's gnss.gps_std)
  /// [s] an interval shorter than this is taken as this long (two messages at nearly the same
  /// time: their increments are the sender's, not a speed)
  double min_interval = 0.005;
};

/// Checks each input of the fusion against the limits: "" when it is within them, else why not.
class LimitCheck {
 public:
  explicit LimitCheck(InputLimits l = {}) : l_(l) {}
  /// The input: odometry against the steering bound, and against the speed and yaw-rate bounds
  /// over the interval since its channel's previous increment taken (the first of a channel:
  /// steering only); a ruler detection against the ruler's span; a GPS fix against the jump
  /// from its channel's previous fix. A refused input does not become the channel's previous one.
  std::string check(const core::EngineInput& in);

 private:
  InputLimits l_;
  std::unordered_map<std::string, int64_t> last_utime_;  ///< odometry channels: last taken
  struct Fix {
    int64_t utime;
    double x, y, std;
  };
  std::unordered_map<std::string, Fix> last_fix_;  ///< GPS channels: last fix taken
  std::string checkFix(const std::string& channel, const core::GpsInput& g);
};

}  // namespace lcmloc::bus
