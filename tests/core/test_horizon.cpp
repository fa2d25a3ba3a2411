// The fusion horizon's parts in the engine: the horizon follows the largest expected delay, its
// memory bound releases the oldest input early and says so, an input later than it is counted
// per channel with its lateness, and a watched sensor that stops is said once (and once when it
// resumes) while the estimate goes on.
#include <gtest/gtest.h>

#include <climits>
#include <string>
#include <vector>

#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/sensor_watch.hpp"

using namespace lcmloc::core;

namespace {

EngineInput odo(int64_t utime, int64_t seq) {
  OdometryInput o;
  o.utime = utime;
  o.delta_s = 0.1;
  return EngineInput{"ODOMETRY", seq, utime, o};
}

EngineInput gps(int64_t utime, int64_t seq) {
  GpsInput g;
  g.utime = utime;
  g.seq = seq;
  return EngineInput{"GPS", seq, utime, g};
}

struct Recorder {
  struct Event {
    std::string name, detail;
    int64_t utime;
  };
  std::vector<Event> events;
  std::vector<int64_t> states;  ///< utime of each active state
  EngineOutputs outputs() {
    EngineOutputs o;
    o.on_event = [this](const EngineEvent& e) { events.push_back({eventName(e.kind), eventText(e), e.utime}); };
    o.on_state = [this](const std::string&, bool active, const FilterState& s) {
      if (active) states.push_back(s.utime);
    };
    return o;
  }
  std::vector<Event> named(const std::string& name) const {
    std::vector<Event> out;
    for (const auto& e : events)
      if (e.name == name) out.push_back(e);
    return out;
  }
};

}  // namespace

TEST(Horizon, FollowsTheLargestExpectedDelay) {
  EngineConfig c;
  c.reorder_window_us = 50000;
  EXPECT_EQ(c.horizonUs(), 50000);
  c.sensors["GPS"] = SensorExpectation{200000, 0};
  c.sensors["VISION"] = SensorExpectation{120000, 0};
  EXPECT_EQ(c.horizonUs(), 200000);
  c.reorder_window_us = 300000;
  EXPECT_EQ(c.horizonUs(), 300000);
  c.reorder_window_us = 50000;
  Recorder r;
  FusionEngine e(c, {}, r.outputs());
  EXPECT_EQ(e.horizonUs(), 200000);
  // An odometry message 150 ms behind the newest is still taken: the horizon, not the window.
  ASSERT_TRUE(e.push(odo(1000000, 0)));
  ASSERT_TRUE(e.push(odo(1300000, 1)));
  EXPECT_TRUE(e.push(odo(1150000, 2)));
  EXPECT_EQ(e.counters().too_old, 0);
}

TEST(Horizon, AnInputLaterThanTheHorizonIsCountedPerChannelWithItsLateness) {
  EngineConfig c;
  c.reorder_window_us = 100000;
  Recorder r;
  FusionEngine e(c, {}, r.outputs());
  for (int k = 0; k <= 30; ++k) ASSERT_TRUE(e.push(odo(1000000 + k * 10000, k)));  // newest 1.3 s
  EXPECT_FALSE(e.push(gps(1100000, 0)));  // 0.2 s after its time
  EXPECT_FALSE(e.push(gps(1150000, 1)));  // 0.15 s
  EXPECT_FALSE(e.push(odo(1300000, 30)));  // a duplicate of one still queued: not late
  EXPECT_EQ(e.counters().too_old, 3);
  ASSERT_EQ(e.lateInputs().size(), 1u);
  EXPECT_EQ(e.lateInputs().at("GPS").count, 2);
  EXPECT_EQ(e.lateInputs().at("GPS").max_lateness_us, 200000);
  const auto late = r.named("too_old");
  ASSERT_EQ(late.size(), 3u);
  EXPECT_EQ(late[0].detail,
            "GPS seq 0 utime 1100000: older than already processed utime 1190000 (0.090 s behind it); it came 0.200 s "
            "after its time (the newest input: utime 1300000), the horizon is 0.100 s");
  EXPECT_EQ(late[2].detail, "ODOMETRY seq 30 utime 1300000: duplicate");
}

TEST(Horizon, TheLatenessOfACorruptTimeFarInThePastIsSaturatedNotOverflowed) {
  EngineConfig c;
  c.reorder_window_us = 100000;
  c.max_time_jump_us = 0;  // no time-jump guard: the corrupt time reaches the reorder window
  Recorder r;
  FusionEngine e(c, {}, r.outputs());
  for (int k = 0; k <= 30; ++k) ASSERT_TRUE(e.push(odo((int64_t{1} << 62) + k * 10000, k)));
  EXPECT_FALSE(e.push(gps(INT64_MIN + 5, 0)));  // newest - its time does not fit in int64
  EXPECT_EQ(e.lateInputs().at("GPS").max_lateness_us, INT64_MAX);
  const auto late = r.named("too_old");
  ASSERT_EQ(late.size(), 1u);
  EXPECT_NE(late[0].detail.find("it came 13835058055282."), std::string::npos) << late[0].detail;
}

TEST(Horizon, AtItsMemoryBoundTheOldestIsReleasedEarlyCountedAndSaidOncePerStretch) {
  EngineConfig c;
  c.reorder_window_us = 1000000;  // 1 s: 100 odometry inputs at 100 Hz
  c.max_queued = 20;
  Recorder r;
  FusionEngine e(c, {}, r.outputs());
  for (int k = 0; k < 60; ++k) ASSERT_TRUE(e.push(odo(1000000 + k * 10000, k)));
  EXPECT_EQ(e.counters().released_early, 40);
  EXPECT_EQ(e.counters().processed, 40);  // nothing is older than the horizon yet: all early
  ASSERT_EQ(r.states.size(), 40u);
  const auto full = r.named("horizon_full");
  ASSERT_EQ(full.size(), 1u);
  EXPECT_EQ(full[0].detail,
            "ODOMETRY seq 0 utime 1000000: released before its time: the horizon (1.000 s) holds at most 20 inputs "
            "(fusion.max_queued); 1 released early so far");
  // An input older than what went early is late, like any other.
  EXPECT_FALSE(e.push(gps(1100000, 0)));
  EXPECT_EQ(e.lateInputs().at("GPS").count, 1);
  // Room again (everything queued processed): the next stretch is said again.
  e.flush();
  for (int k = 0; k < 30; ++k) ASSERT_TRUE(e.push(odo(1600000 + k * 10000, 100 + k)));
  EXPECT_EQ(r.named("horizon_full").size(), 2u);
  EXPECT_EQ(e.counters().released_early, 50);
}

TEST(Horizon, AWatchedSensorThatStopsIsSaidOnceAndOnceWhenItResumesAndNothingStalls) {
  EngineConfig c;
  c.reorder_window_us = 50000;
  c.sensors["GPS"] = SensorExpectation{100000, 100000};  // 10 Hz, up to 0.1 s late: silent > 0.6 s
  c.sensors["LANDMARKS"] = SensorExpectation{0, 0};      // not watched
  Recorder r;
  FusionEngine e(c, {}, r.outputs());
  int64_t seq = 0, gps_seq = 0;
  auto drive = [&](int64_t from, int64_t to, bool with_gps) {
    for (int64_t t = from; t < to; t += 10000) {
      ASSERT_TRUE(e.push(odo(t, seq++)));
      if (with_gps && t % 100000 == 0) {
        ASSERT_TRUE(e.push(gps(t, gps_seq++)));
      }
    }
  };
  drive(1000000, 3000000, true);
  EXPECT_TRUE(r.named("sensor_stopped").empty());
  drive(3000000, 5000000, false);  // the receiver stops for 2 s
  const auto stopped = r.named("sensor_stopped");
  ASSERT_EQ(stopped.size(), 1u);
  EXPECT_EQ(stopped[0].detail,
            "GPS: no input since utime 2900000, 0.610 s of message time before the newest input (utime 3510000), more "
            "than 0.600 s (its period 0.100 s)");
  drive(5000000, 6000000, true);
  const auto resumed = r.named("sensor_resumed");
  ASSERT_EQ(resumed.size(), 1u);
  EXPECT_EQ(resumed[0].detail, "GPS: input again at utime 5000000 after none since utime 2900000");
  EXPECT_EQ(r.named("sensor_stopped").size(), 1u);
  // Nothing waited for it: a state after every odometry input older than the horizon (the GPS's
  // 0.1 s delay: 1.00 to 5.88 s, the newest at 5.99 s).
  EXPECT_EQ(e.counters().too_old, 0);
  EXPECT_EQ(r.states.size(), 489u);
}

TEST(SensorWatch, ANeverSeenChannelStopsCountingFromTheFirstInputAndATimeBaseStartsItsClockAgain) {
  SensorWatch w({{"GPS", SensorExpectation{0, 100000}}, {"ODOMETRY", SensorExpectation{}}});
  EXPECT_TRUE(w.active());
  std::vector<std::string> said;
  auto say = [&](EventKind k, int64_t, const events::SensorSilence& s) { said.push_back(std::string(eventName(k)) + " " + s.channel); };
  w.input("ODOMETRY", 1000000, 1000000, say);
  w.input("ODOMETRY", 1500000, 1500000, say);
  EXPECT_TRUE(said.empty());
  w.input("ODOMETRY", 1500001, 1500001, say);  // 0.5 s + 1 us since the clock started
  EXPECT_EQ(said, (std::vector<std::string>{"sensor_stopped GPS"}));
  EXPECT_EQ(w.stopped(), 1);
  w.restart();
  EXPECT_EQ(w.stopped(), 0);
  w.input("ODOMETRY", 9000000, 9000000, say);
  w.input("ODOMETRY", 9400000, 9400000, say);
  EXPECT_EQ(said.size(), 1u);
  EXPECT_FALSE(SensorWatch({{"GPS", SensorExpectation{200000, 0}}}).active());
}
