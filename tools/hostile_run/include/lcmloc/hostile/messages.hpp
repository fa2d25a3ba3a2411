#pragma once
// Bad messages of every kind for every input channel of the fusion daemon (test_hostile_input
// over the MemoryBus, test_hostile_process over real LCM, lcmloc-hostile-run on a running
// system): undecodable bytes, a right fingerprint
// with a cut body, NaN, a negative sigma (or the kind's own bad value), a time that is huge,
// negative or behind the time-jump guard, a flood of copies.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"

namespace lcmloc::hostile {

inline lcmloc::odometry_t odometry(int64_t seq, int64_t utime) {
  lcmloc::odometry_t m{};
  m.utime = utime;
  m.seq = seq;
  m.delta_s = 0.1;
  m.has_steering = true;
  m.steering = 0.01;
  m.delta_theta = 0.1 * std::tan(0.01) / 2.5;
  return m;
}

/// A valid message of each input type, and the same with one field made bad.
struct Kind {
  std::string channel;
  std::function<std::vector<uint8_t>(int64_t seq, int64_t utime, const std::string& bad)> make;
};

template <typename T>
inline std::vector<uint8_t> enc(const T& m) {
  return bus::MemoryBus::encode(m);
}

inline std::vector<Kind> kinds(const app::ChannelConfig& ch) {
  std::vector<Kind> k;
  k.push_back({ch.odometry, [](int64_t seq, int64_t t, const std::string& bad) {
                 auto m = odometry(seq, t);
                 if (bad == "nan") m.delta_s = NAN;
                 if (bad == "sigma") m.delta_theta = INFINITY;  // (no sigma field: an Inf instead)
                 return enc(m);
               }});
  k.push_back({ch.magruler.front(), [](int64_t seq, int64_t t, const std::string& bad) {
                 lcmloc::magruler_t m{};
                 m.utime = t;
                 m.seq = seq;
                 m.num_sensors = 13;
                 m.readings.assign(13, 0.45);
                 m.detected = true;
                 m.lateral_offset = bad == "nan" ? NAN : 0.1;
                 m.quality = bad == "sigma" ? -1.0 : 0.9;
                 return enc(m);
               }});
  k.push_back({ch.imu, [](int64_t seq, int64_t t, const std::string& bad) {
                 lcmloc::imu_t m{};
                 m.utime = t;
                 m.seq = seq;
                 m.accel[2] = 9.81;
                 m.mag[0] = 0.2;
                 if (bad == "nan") m.gyro[2] = NAN;
                 if (bad == "sigma") m.accel[0] = -1e9;
                 return enc(m);
               }});
  k.push_back({ch.gps, [](int64_t seq, int64_t t, const std::string& bad) {
                 lcmloc::gps_fix_t m{};
                 m.utime = t;
                 m.seq = seq;
                 m.latitude = 48.0;
                 m.longitude = 11.0;
                 m.fix_type = 3;
                 m.satellites = 8;
                 m.hdop = 1.0;
                 m.position_std = bad == "sigma" ? -2.0 : 2.0;
                 if (bad == "nan") m.longitude = NAN;
                 return enc(m);
               }});
  k.push_back({ch.landmarks, [](int64_t seq, int64_t t, const std::string& bad) {
                 lcmloc::landmark_obs_t m{};
                 m.utime = t;
                 m.seq = seq;
                 m.landmark_id = 1;
                 m.range = bad == "nan" ? NAN : 5.0;
                 m.range_std = bad == "sigma" ? -0.1 : 0.1;
                 return enc(m);
               }});
  k.push_back({ch.beacons, [](int64_t seq, int64_t t, const std::string& bad) {
                 lcmloc::beacon_range_t m{};
                 m.utime = t;
                 m.seq = seq;
                 m.beacon_id = 1;
                 m.range = bad == "nan" ? NAN : 5.0;
                 m.range_std = bad == "sigma" ? -0.1 : 0.1;
                 return enc(m);
               }});
  k.push_back({ch.vision, [](int64_t seq, int64_t t, const std::string& bad) {
                 lcmloc::landmark_bearings_t m{};
                 m.utime = t;
                 m.seq = seq;
                 m.count = 3;
                 m.landmark_ids = {1, 2, 3};
                 m.bearings = {0.1, bad == "nan" ? NAN : 1.0, 2.0};
                 m.bearing_std = bad == "sigma" ? -0.01 : 0.01;
                 return enc(m);
               }});
  return k;
}

/// The kinds of bad message, in the order the tests send them.
inline const std::vector<std::string>& badKinds() {
  static const std::vector<std::string> k{"undecodable", "cut", "nan", "sigma", "huge_time", "negative_time",
                                          "time_back", "flood"};
  return k;
}

/// The bytes of one bad message of `bad` kind on `kind`'s channel, with seq s at time t (a time
/// of its own for the time kinds); flood: one valid message (sent 100 times).
inline std::vector<uint8_t> badMessage(const Kind& kind, const std::string& bad, int64_t s, int64_t t) {
  std::vector<uint8_t> bytes = kind.make(s, t, bad);
  if (bad == "undecodable") bytes = {0xde, 0xad, 0xbe, 0xef, 1, 2, 3};
  if (bad == "cut") bytes.resize(bytes.size() / 2);
  if (bad == "huge_time") bytes = kind.make(s, int64_t{1} << 61, "");
  if (bad == "negative_time") bytes = kind.make(s, -5, "");
  if (bad == "time_back") bytes = kind.make(s, t - 1'500'000, "");  // beyond fusion.max_time_jump
  return bytes;
}

/// What the daemon's stop status says of every channel after each kind was sent once: the
/// undecodable and cut undecodable; NaN, the bad sigma and the negative time invalid; the huge
/// time too new; 99 of the 100 copies and the time behind too old.
inline std::vector<std::string> expectedCounts() {
  return {" undecodable 2", " invalid 3", " too_new 1", " too_old 100"};
}

/// Decodable messages with wrong values, as a second publisher would send them (a driver started
/// twice, lcm-logplayer on the live network): the odometry driving backwards 1 m per message
/// with the steering at -1 rad, a ruler detection at offset 0 with quality 0; the other kinds'
/// valid message. variant picks one of a few such messages.
inline std::vector<uint8_t> wrongMessage(const Kind& kind, const app::ChannelConfig& ch, int variant, int64_t s,
                                         int64_t t) {
  if (kind.channel == ch.odometry) {
    auto m = odometry(s, t);
    if (variant % 2 == 0) m.delta_s = -1.0;
    else m.steering = -1.0;
    return enc(m);
  }
  if (std::find(ch.magruler.begin(), ch.magruler.end(), kind.channel) != ch.magruler.end()) {
    lcmloc::magruler_t m{};
    m.utime = t;
    m.seq = s;
    m.num_sensors = 13;
    m.readings.assign(13, 0.0);
    m.detected = true;
    m.lateral_offset = 0.0;
    m.quality = 0.0;
    return enc(m);
  }
  return kind.make(s, t, "");
}

/// Commands with bad parameters on the control channel: an unknown command, a switch to a
/// filter that does not exist, to a filter with parameters that are no YAML, a pose that is NaN,
/// a pose with a negative sigma. variant picks one.
inline std::vector<uint8_t> badControl(int variant, int64_t s, int64_t t) {
  lcmloc::fusion_control_t m{};
  m.utime = t;
  m.seq = s;
  switch (variant % 5) {
    case 0: m.command = 99; break;
    case 1: m.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER; m.filter = "no_such_filter"; break;
    case 2: m.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER; m.filter = "ukf"; m.parameters = "{q: [1,"; break;
    case 3: m.command = lcmloc::fusion_control_t::CMD_SET_POSE; m.pose[0] = NAN; m.pose_std[0] = 1.0; break;
    default: m.command = lcmloc::fusion_control_t::CMD_SET_POSE; m.pose_std[0] = -1.0; break;
  }
  return enc(m);
}

}  // namespace lcmloc::hostile
