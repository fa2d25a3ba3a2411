// Every kind of bad message on every input channel of a running daemon (over the MemoryBus):
// undecodable bytes, a right fingerprint with a cut body, NaN, a negative sigma, a time that is
// huge, negative or far back, a flood of copies. After each, the pose is finite, POSE keeps the
// odometry's rate, and the status counts the drop under its channel and reason.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "daemon/daemon.hpp"
#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/magruler_t.hpp"

using namespace lcmloc;

namespace {

constexpr int64_t kT0 = 1000000;
constexpr int64_t kStep = 10000;  // 100 Hz odometry

lcmloc::odometry_t odometry(int64_t seq, int64_t utime) {
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
std::vector<uint8_t> enc(const T& m) {
  return bus::MemoryBus::encode(m);
}

std::vector<Kind> kinds(const app::ChannelConfig& ch) {
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

}  // namespace

TEST(HostileInput, EveryKindOfBadMessageOnEveryInputChannelIsCountedAndDroppedAndThePoseGoesOn) {
  const app::SystemConfig cfg = app::loadSystemConfig(LCMLOC_PAPER_YAML);
  bus::MemoryBus bus;
  fusion::FusionDaemon daemon(cfg, bus);
  const auto all = kinds(cfg.channels);
  const std::vector<std::string> bad_kinds{"undecodable", "cut", "nan", "sigma", "huge_time", "negative_time",
                                           "time_back", "flood"};
  std::map<std::string, int64_t> seq;
  int64_t k = 0;
  auto odo = [&](int64_t n) {
    for (int64_t i = 0; i < n; ++i, ++k) {
      bus.inject(cfg.channels.odometry, odometry(k, kT0 + k * kStep));
      bus.deliverAll();
    }
  };
  odo(100);
  for (const auto& bad : bad_kinds) {
    for (const auto& kind : all) {
      // From the channel's own publisher: on ODOMETRY the next message of the stream is the bad
      // one (its seq and time), elsewhere a message between two odometry messages.
      const bool odometry_channel = kind.channel == cfg.channels.odometry;
      const int64_t t = odometry_channel ? kT0 + k * kStep : kT0 + k * kStep + 5000;
      const int64_t s = odometry_channel ? k++ : seq[kind.channel]++;
      std::vector<uint8_t> bytes = kind.make(s, t, bad);
      if (bad == "undecodable") bytes = {0xde, 0xad, 0xbe, 0xef, 1, 2, 3};
      if (bad == "cut") bytes.resize(bytes.size() / 2);
      if (bad == "huge_time") bytes = kind.make(s, int64_t{1} << 61, "");
      if (bad == "negative_time") bytes = kind.make(s, -5, "");
      if (bad == "time_back") bytes = kind.make(s, t - 1'500'000, "");  // beyond fusion.max_time_jump
      const int copies = bad == "flood" ? 100 : 1;
      for (int c = 0; c < copies; ++c) bus.inject(kind.channel, bytes);  // (flood: copies of one message)
      bus.deliverAll();
      odo(10);
    }
  }
  odo(300);
  daemon.shutdown();
  const auto poses = bus.decoded<lcmloc::pose_t>(cfg.channels.pose);
  ASSERT_GT(poses.size(), 500u);
  int64_t worst_gap = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (double v : poses[i].state) ASSERT_TRUE(std::isfinite(v)) << i;
    if (i > 0) worst_gap = std::max(worst_gap, poses[i].utime - poses[i - 1].utime);
  }
  EXPECT_LE(worst_gap, 2 * kStep) << "POSE kept the odometry's rate";
  const auto st = bus.decoded<lcmloc::fusion_status_t>(cfg.channels.status);
  ASSERT_FALSE(st.empty());
  ASSERT_EQ(st.back().event, "stopped");
  // Per channel: undecodable and cut undecodable; NaN, a negative sigma (or its kind's bad
  // value) and a negative time invalid; a time 2^61 too new; 99 of the 100 copies and the time
  // 1.5 s back too old.
  for (const auto& kind : all)
    for (const std::string& counted : {" undecodable 2", " invalid 3", " too_new 1", " too_old 100"})
      EXPECT_NE(st.back().detail.find(kind.channel + counted), std::string::npos)
          << kind.channel << counted << "\n" << st.back().detail;
  // The status events stayed few: at most 5 per channel and reason in a status period.
  int64_t rejected_events = 0;
  for (const auto& s : st) rejected_events += s.event == "rejected_input";
  EXPECT_LE(rejected_events, static_cast<int64_t>(all.size() * 4 * fusion::RejectBook::kEventsPerPeriod));
  // ODOMETRY's undecodable and cut messages had their seq in the stream: they count as lost.
  EXPECT_EQ(daemon.gaps(), 2);
}
