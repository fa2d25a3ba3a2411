// The daemon intake's guards against wrong but decodable input: a second publisher on a channel
// (bus::StreamGuard) and physical limits (bus::LimitCheck).
#include <gtest/gtest.h>

#include <limits>

#include "lcmloc/bus/input_limits.hpp"
#include "lcmloc/bus/stream_guard.hpp"

using namespace lcmloc;
using Kind = bus::StreamVerdict::Kind;

namespace {
constexpr int64_t kT0 = 1'000'000'000;
constexpr int64_t kPeriod = 10'000;  // 100 Hz
}  // namespace

TEST(StreamGuard, ASecondPublisherIsHeldApartFromItsSecondMessageAndReportedOnce) {
  bus::StreamGuard g;
  int64_t held = 0, detected = 0, taken_second = 0;
  for (int i = 0; i < 300; ++i) {
    const int64_t t = kT0 + i * kPeriod;
    EXPECT_EQ(g.observe("ODOMETRY", 5000 + i, t).kind, Kind::Taken) << i;
    if (i < 100) continue;
    const auto v = g.observe("ODOMETRY", i - 100, t + 3000);  // another stream from seq 0, times near ours
    held += v.held();
    detected += v.detected;
    taken_second += v.kind == Kind::Taken;
    if (v.detected) {
      EXPECT_EQ(v.first_seq, 0);
      EXPECT_EQ(v.first_utime, kT0 + 100 * kPeriod + 3000);
      EXPECT_NE(v.describe("ODOMETRY").find("a second publisher (first seq 0"), std::string::npos) << v.describe("ODOMETRY");
    }
  }
  EXPECT_EQ(taken_second, 1);  // its first message: a lone corrupt seq looks the same
  EXPECT_EQ(held, 199);
  EXPECT_EQ(detected, 1);
  EXPECT_EQ(g.detections(), 1);
  // Another channel is another matter.
  EXPECT_EQ(g.observe("GPS", 0, kT0).kind, Kind::Taken);
}

TEST(StreamGuard, ALoneCorruptSeqCostsNothing) {
  bus::StreamGuard g;
  for (int i = 0; i < 100; ++i) {
    const int64_t seq = i == 50 ? (int64_t{1} << 40) : i;  // one flipped bit
    EXPECT_EQ(g.observe("IMU", seq, kT0 + i * kPeriod).kind, Kind::Taken) << i;
  }
  EXPECT_EQ(g.held(), 0);
}

TEST(StreamGuard, SeqsAndTimesAtTheEndsOfTheirRangeAreComparedWithoutOverflow) {
  // A corrupt seq near INT64_MIN, then one near INT64_MAX: their difference does not fit in
  // int64 (undefined behaviour where it was computed); the second is neither stream's next.
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  bus::StreamGuard g;
  for (int i = 0; i < 10; ++i) g.observe("ODOMETRY", i, kT0 + i * kPeriod);
  EXPECT_EQ(g.observe("ODOMETRY", kMin + 3, kMin).kind, Kind::Taken);  // a lone corrupt seq, so far
  EXPECT_EQ(g.observe("ODOMETRY", kMax - 3, kMax).kind, Kind::Taken);  // another: it does not go on from the first
  EXPECT_EQ(g.observe("ODOMETRY", 10, kT0 + 10 * kPeriod).kind, Kind::Taken);
  const auto v = g.observe("ODOMETRY", kMax - 2, kMax);  // this one goes on from it: a second publisher
  EXPECT_TRUE(v.held());
  EXPECT_EQ(v.first_seq, kMax - 3);
  EXPECT_EQ(v.first_utime, kMax);
  EXPECT_EQ(g.held(), 1);
}

TEST(StreamGuard, APublisherThatRestartsIsTakenAndReplacesItsSilentStream) {
  bus::StreamGuard g;
  for (int i = 0; i < 5000; ++i) g.observe("ODOMETRY", i, kT0 + i * kPeriod);
  // Started over: seq from 0, time from the start again (a log played again); the old stream is silent.
  int replaced = 0;
  for (int i = 0; i < 400; ++i) {
    const auto v = g.observe("ODOMETRY", i, kT0 + i * kPeriod);
    EXPECT_FALSE(v.held()) << i;
    if (v.kind == Kind::Replaced) {
      ++replaced;
      EXPECT_EQ(i, 200);  // after 2 s of its message time without the old stream
      EXPECT_NE(v.describe("ODOMETRY").find("replaces the one silent since seq 4999"), std::string::npos);
    }
  }
  EXPECT_EQ(replaced, 1);
  // The old stream back now is the other one, and held once the new one has gone on.
  g.observe("ODOMETRY", 5000, kT0 + 5000 * kPeriod);  // (its first message: taken)
  g.observe("ODOMETRY", 400, kT0 + 400 * kPeriod);
  EXPECT_TRUE(g.observe("ODOMETRY", 5001, kT0 + 5001 * kPeriod).held());
}

TEST(StreamGuard, OneMessageWithAWrongTimeDoesNotReplaceTheEstablishedStream) {
  bus::StreamGuard g;
  for (int i = 0; i < 100; ++i) g.observe("ODOMETRY", i, kT0 + i * kPeriod);
  g.observe("ODOMETRY", 7000, kT0 + 100 * kPeriod);  // another stream's first
  g.observe("ODOMETRY", 100, kT0 + 100 * kPeriod);
  const auto v = g.observe("ODOMETRY", 7001, int64_t{1} << 61);  // its second, far in the future
  EXPECT_TRUE(v.held());
  EXPECT_EQ(g.observe("ODOMETRY", 101, kT0 + 101 * kPeriod).kind, Kind::Taken);
}

TEST(StreamGuard, AStreamThatStartsOverWithinItsOwnSeqsIsOneStream) {
  bus::StreamGuard g;
  for (int i = 0; i < 100; ++i) g.observe("ODOMETRY", i, kT0 + i * kPeriod);
  for (int i = 0; i < 300; ++i) EXPECT_FALSE(g.observe("ODOMETRY", i, kT0 + i * kPeriod).held()) << i;
  EXPECT_EQ(g.held(), 0);
}

TEST(StreamGuard, ASlowEstablishedStreamIsNotReplacedByAFastIntruderWhichIsHeldFromItsSecondMessage) {
  bus::StreamGuard g;
  for (int i = 0; i < 10; ++i) g.observe("GPS", i, kT0 + i * 1'000'000);  // 1 Hz
  int64_t held = 0;
  for (int k = 0; k < 100; ++k) {  // an intruder at 10 Hz for 10 s, joined mid-way (seq 7000)
    const int64_t t = kT0 + 10'000'000 + k * 100'000;
    if (k % 10 == 0) {
      EXPECT_EQ(g.observe("GPS", 10 + k / 10, t).kind, Kind::Taken) << k;
    }
    const auto v = g.observe("GPS", 7000 + k, t + 1);
    EXPECT_NE(v.kind, Kind::Replaced) << k;
    held += v.held();
  }
  EXPECT_EQ(held, 99);  // its first message is taken (a lone corrupt seq looks the same)
}

// The same intruder from seq 0 looks like the GPS driver restarted: it is taken until the
// established stream's next message (one of its periods), held from then on.
TEST(StreamGuard, AnIntruderFromSeqZeroIsTakenAsARestartUntilTheEstablishedStreamGoesOn) {
  bus::StreamGuard g;
  for (int i = 0; i < 10; ++i) g.observe("GPS", 100 + i, kT0 + i * 1'000'000);
  int64_t held = 0;
  for (int k = 0; k < 100; ++k) {
    const int64_t t = kT0 + 10'000'000 + k * 100'000;
    if (k % 10 == 0) {
      EXPECT_EQ(g.observe("GPS", 110 + k / 10, t).kind, Kind::Taken) << k;
    }
    const auto v = g.observe("GPS", k, t + 1);
    EXPECT_NE(v.kind, Kind::Replaced) << k;
    held += v.held();
  }
  EXPECT_EQ(held, 90);
}

// A sparse established stream (a ruler publishing at markers, one message every 1.3 s) and a
// second publisher at 20 Hz near the live time with one message far in the future among them:
// that one message does not make the intruder span the established stream's silence at once
// (it replaced the ruler 0.66 s after the ruler's last message, in the live hostile run).
TEST(StreamGuard, OneFarFutureTimeAmongAnIntrudersMessagesDoesNotReplaceASparseStream) {
  bus::StreamGuard g;
  g.observe("MAGRULER", 0, kT0);
  int64_t held = 0;
  for (int k = 0; k < 60; ++k) {  // 3 s at 20 Hz from 50 ms after the ruler's first message
    const int64_t t = kT0 + 50'000 + k * 50'000;
    if (k == 26) {
      EXPECT_EQ(g.observe("MAGRULER", 1, kT0 + 1'330'000).kind, Kind::Taken);  // the ruler's next
    }
    if (k == 52) {
      EXPECT_EQ(g.observe("MAGRULER", 2, kT0 + 2'660'000).kind, Kind::Taken);
    }
    const auto v = g.observe("MAGRULER", 1'000'000'000 + k, k == 3 ? int64_t{1} << 61 : t);
    EXPECT_NE(v.kind, Kind::Replaced) << k;
    held += v.held();
  }
  EXPECT_EQ(held, 59);  // held from its second message on
}

// Fault markers: the injector publishes twice in a run, 7.7 s apart. A second publisher that
// joins mid-way between them, at 20 Hz with times near the live one (one of them 1.5 s back),
// never feeds the fusion beyond its first message and never replaces the silent injector.
TEST(StreamGuard, AnIntruderThatJoinsASparseSilentChannelIsHeldAndNeverReplacesIt) {
  bus::StreamGuard g;
  EXPECT_EQ(g.observe("MAGRULER_FAULT", 0, kT0).kind, Kind::Taken);
  int64_t held = 0, detected = 0;
  for (int k = 0; k < 600; ++k) {  // 30 s
    const int64_t t = kT0 + 400'000 + k * 50'000;
    if (k == 146) {
      EXPECT_EQ(g.observe("MAGRULER_FAULT", 1, kT0 + 7'700'000).kind, Kind::Taken);  // the injector's next
    }
    const auto v = g.observe("MAGRULER_FAULT", 1'000'000'000 + k, k == 1 ? t - 1'500'000 : t);
    EXPECT_NE(v.kind, Kind::Replaced) << k;
    held += v.held();
    detected += v.detected;
    if (v.detected) {
      EXPECT_NE(v.describe("MAGRULER_FAULT").find("a second publisher (first seq 1000000000"), std::string::npos)
          << v.describe("MAGRULER_FAULT");
    }
  }
  EXPECT_EQ(held, 599);
  EXPECT_EQ(detected, 1);
  EXPECT_EQ(g.observe("MAGRULER_FAULT", 2, kT0 + 40'000'000).kind, Kind::Taken);
}

// The daemon started while the drivers run, and the first message it gets on a channel has a
// corrupt seq: the genuine stream (mid-way, not from seq 0) replaces that lone message at its
// second message instead of being held apart for good.
TEST(StreamGuard, AGenuineStreamReplacesALoneCorruptSeqTheChannelBeganWith) {
  bus::StreamGuard g;
  EXPECT_EQ(g.observe("ODOMETRY", int64_t{1} << 40, kT0).kind, Kind::Taken);
  EXPECT_EQ(g.observe("ODOMETRY", 52'000, kT0 + kPeriod).kind, Kind::Taken);  // another stream's first
  const auto v = g.observe("ODOMETRY", 52'001, kT0 + 2 * kPeriod);
  EXPECT_EQ(v.kind, Kind::Replaced);
  EXPECT_TRUE(v.lone);
  EXPECT_NE(v.describe("ODOMETRY").find("replaces the lone message the channel began with (seq 1099511627776"),
            std::string::npos)
      << v.describe("ODOMETRY");
  for (int i = 2; i < 100; ++i) EXPECT_EQ(g.observe("ODOMETRY", 52'000 + i, kT0 + (i + 1) * kPeriod).kind, Kind::Taken);
  EXPECT_EQ(g.held(), 0);
  // Once it has gone on, a stream from mid-way is held again.
  g.observe("ODOMETRY", 9'000'000, kT0 + 101 * kPeriod);
  EXPECT_TRUE(g.observe("ODOMETRY", 9'000'001, kT0 + 102 * kPeriod).held());
}

namespace {
core::EngineInput odo(const std::string& ch, int64_t utime, double ds, double dth, double steering = 0, bool car = false) {
  core::OdometryInput o;
  o.utime = utime;
  o.delta_s = ds;
  o.delta_theta = dth;
  o.steering = steering;
  o.has_steering = car;
  return core::EngineInput{ch, 0, utime, o};
}
}  // namespace

TEST(LimitCheck, OdometryBeyondSpeedYawRateOrSteeringIsRefusedSayingWhich) {
  bus::LimitCheck c;  // 70 m/s, 12 rad/s, 0.8 rad
  EXPECT_EQ(c.check(odo("ODOMETRY", kT0, 0.1, 0.0)), "");  // the first: no interval yet
  EXPECT_EQ(c.check(odo("ODOMETRY", kT0 + kPeriod, 0.3, 0.08)), "");  // 30 m/s, 8 rad/s (a small robot spinning)
  const std::string fast = c.check(odo("ODOMETRY", kT0 + 2 * kPeriod, -1.0, 0.0));  // -1 m in 10 ms
  EXPECT_NE(fast.find("100 m/s, beyond fusion.limits.max_speed 70"), std::string::npos) << fast;
  // The refused one did not move the channel's time: the next is over 20 ms.
  EXPECT_EQ(c.check(odo("ODOMETRY", kT0 + 3 * kPeriod, 1.2, 0.0)), "");  // 60 m/s over 20 ms
  const std::string spin = c.check(odo("ODOMETRY", kT0 + 4 * kPeriod, 0.1, 0.15));  // 15 rad/s
  EXPECT_NE(spin.find("max_yaw_rate"), std::string::npos) << spin;
  const std::string steer = c.check(odo("ODOMETRY", kT0 + 4 * kPeriod, 0.1, 0.0, -1.0, true));
  EXPECT_NE(steer.find("steering angle -1 rad beyond fusion.limits.max_steering 0.8"), std::string::npos) << steer;
  // Each channel has its own interval; other inputs are not odometry's business.
  EXPECT_EQ(c.check(odo("ODOMETRY_2", kT0 + 4 * kPeriod, 5.0, 0.0)), "");
  EXPECT_EQ(c.check(core::EngineInput{"GPS", 0, kT0, core::GpsInput{}}), "");
  // 0 = off.
  bus::InputLimits none;
  none.max_speed = none.max_yaw_rate = none.max_steering = 0;
  bus::LimitCheck off(none);
  off.check(odo("ODOMETRY", kT0, 0.1, 0.0));
  EXPECT_EQ(off.check(odo("ODOMETRY", kT0 + kPeriod, -1.0, 1.0, -1.0, true)), "");
}

TEST(LimitCheck, ARulerDetectionBeyondItsSpanAndAFixThatJumpsTooFarAreRefused) {
  bus::InputLimits l;
  l.max_lateral_offset = 0.75;  // a ruler of half width 0.5
  l.gps_std = 2.0;
  bus::LimitCheck c(l);
  core::RulerDetection d;
  d.lateral_offset = 0.6;
  EXPECT_EQ(c.check(core::EngineInput{"MAGRULER", 0, kT0, d}), "");
  d.lateral_offset = -0.9;
  const std::string span = c.check(core::EngineInput{"MAGRULER", 1, kT0, d});
  EXPECT_NE(span.find("lateral offset -0.9 m beyond the ruler's span (0.75 m)"), std::string::npos) << span;
  auto fix = [](int64_t t, double x, double y, double sd = 0) {
    core::GpsInput g;
    g.utime = t;
    g.x = x;
    g.y = y;
    g.position_std = sd;
    return core::EngineInput{"GPS", 0, t, g};
  };
  EXPECT_EQ(c.check(fix(kT0, 0, 0)), "");
  EXPECT_EQ(c.check(fix(kT0 + 1'000'000, 60, 20)), "");  // 63 m in 1 s: within 70 m/s + 10 sigma
  // 2 km in 1 s: beyond 70 m/s and 10 sigma of the two fixes (2.83 m each way): refused, and the
  // next fix is compared with the last one taken.
  const std::string jump = c.check(fix(kT0 + 2'000'000, 2060, 20));
  EXPECT_NE(jump.find("fix 2000 m from the previous one 1 s before, beyond fusion.limits.max_speed 70"),
            std::string::npos)
      << jump;
  EXPECT_EQ(c.check(fix(kT0 + 3'000'000, 70, 20)), "");
  // A fix's own sigma widens the bound.
  EXPECT_EQ(c.check(fix(kT0 + 4'000'000, 700, 20, 100.0)), "");
  // No fix: nothing to check.
  core::GpsInput none;
  none.has_fix = false;
  EXPECT_EQ(c.check(core::EngineInput{"GPS", 0, kT0 + 5'000'000, none}), "");
}
