// The daemon's wall-clock timing (FUSION_TIMING): the figures from given arrival times, the
// daemon measuring through it over the MemoryBus, its POSE unchanged by it, the control pose
// only with Options::control; and lcmloc-ctl's table of it.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "daemon/daemon.hpp"
#include "daemon/timing.hpp"
#include "hostile_messages.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/ctl/status.hpp"

using namespace lcmloc;

using lcmloc::hostile::odometry;  // (10 m/s with a slight steer)

TEST(DaemonTiming, DelayAgeRateAndStepQuantilesOverTheWindow) {
  fusion::DaemonTiming t(1000000);  // 1 s window
  // 100 messages 10 ms apart, arriving 2 ms late, the last one 9 ms late; an old one 1.5 s before.
  t.arrived("GPS", 0, 500000);
  EXPECT_DOUBLE_EQ(t.report(1000000).rate[0], 2.0) << "one message in its first 0.5 s";
  for (int k = 0; k < 100; ++k) t.arrived("ODOMETRY", 1000000 + k * 10000, 1000000 + k * 10000 + (k == 99 ? 9000 : 2000));
  for (int k = 1; k <= 100; ++k) t.step(k * 1e-5, 1990000);  // 10 us .. 1 ms
  const auto r = t.report(1999000 + 3000);  // 3 ms after the last arrival; the first one 1 s before
  ASSERT_EQ(r.num_channels, 2);
  ASSERT_EQ(r.channel[1], "ODOMETRY");
  EXPECT_EQ(r.count[1], 100);
  EXPECT_DOUBLE_EQ(r.rate[1], 100.0);
  EXPECT_NEAR(r.delay_p50[1], 0.002, 1e-12);
  EXPECT_NEAR(r.delay_max[1], 0.009, 1e-12);
  EXPECT_NEAR(r.age[1], 0.003, 1e-12);
  EXPECT_EQ(r.channel[0], "GPS");
  EXPECT_EQ(r.count[0], 0) << "older than the window";
  EXPECT_NEAR(r.age[0], 1.502, 1e-12);
  EXPECT_EQ(r.steps, 100);
  EXPECT_NEAR(r.step_p50, 50e-5, 1e-12);
  EXPECT_NEAR(r.step_p99, 99e-5, 1e-12);
  EXPECT_NEAR(r.step_max, 100e-5, 1e-12);
  std::ostringstream text;
  ctl::printTiming(text, r);
  EXPECT_NE(text.str().find("ODOMETRY"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("p99 0.990 ms"), std::string::npos) << text.str();
}

// The engine's late inputs by channel beside each channel's delay: FUSION_TIMING's late and
// late_max, printed by lcmloc-ctl status with the horizon.
TEST(DaemonTiming, LateInputsArePerChannelBesideTheDelays) {
  fusion::DaemonTiming t(1000000);
  t.arrived("GPS", 1000000, 1250000);
  t.arrived("ODOMETRY", 1240000, 1250000);
  std::map<std::string, core::LateInputs> late;
  late["GPS"] = core::LateInputs{3, 212000};
  auto r = t.report(1300000, late);
  r.horizon = 0.1;
  r.released_early = 4;
  ASSERT_EQ(r.num_channels, 2);
  ASSERT_EQ(r.channel[0], "GPS");
  EXPECT_EQ(r.late[0], 3);
  EXPECT_NEAR(r.late_max[0], 0.212, 1e-12);
  EXPECT_EQ(r.late[1], 0);
  EXPECT_EQ(r.late_max[1], 0.0);
  std::ostringstream text;
  ctl::printTiming(text, r);
  EXPECT_NE(text.str().find("late max ms"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("      3     212.000"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("horizon 0.100 s"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("released early at its memory bound: 4"), std::string::npos) << text.str();
}

// Timing measured or not, control pose or not: the daemon's POSE is the same bytes.
TEST(DaemonTiming, AMessageTimeAtTheEndOfItsRangeGivesAFiniteDelay) {
  // A corrupt utime: received - message time does not fit in int64 (undefined behaviour where it
  // was computed in integers); the delay is taken in doubles.
  fusion::DaemonTiming t(1000000);
  t.arrived("ODOMETRY", std::numeric_limits<int64_t>::min(), 1000000);
  t.arrived("ODOMETRY", std::numeric_limits<int64_t>::max(), 1000001);
  const auto r = t.report(1000002);
  ASSERT_EQ(r.num_channels, 1);
  EXPECT_GT(r.delay_max[0], 9.2e12);  // s: the first one's, INT64_MAX us behind
  EXPECT_LT(r.delay_p50[0], -9.2e12);
}

TEST(DaemonTiming, TheDaemonMeasuresEachMessageAndItsPoseIsTheSame) {
  const app::SystemConfig cfg = app::loadSystemConfig(LCMLOC_PAPER_YAML);
  auto run = [&](fusion::DaemonTiming* timing, bool control) {
    bus::MemoryBus bus;
    fusion::FusionDaemon d(cfg, bus, fusion::FusionDaemon::Options{false, false, control, timing});
    for (int64_t k = 0; k < 200; ++k) {
      bus.setRecvUtime(1000000 + k * 10000 + 3000);
      bus.inject(cfg.channels.odometry, odometry(k, 1000000 + k * 10000));
      bus.deliverAll();
    }
    d.shutdown();
    return std::make_pair(bus.published(cfg.channels.pose), bus.published(cfg.channels.pose_control));
  };
  fusion::DaemonTiming timing;
  const auto [plain, no_control] = run(nullptr, false);
  const auto [measured, control] = run(&timing, true);
  EXPECT_TRUE(no_control.empty());
  EXPECT_EQ(control.size(), 200u);
  ASSERT_EQ(plain.size(), measured.size());
  for (std::size_t i = 0; i < plain.size(); ++i) ASSERT_EQ(plain[i].data, measured[i].data) << i;
  const auto r = timing.report(1000000 + 199 * 10000 + 3000);
  ASSERT_EQ(r.num_channels, 1);
  EXPECT_EQ(r.count[0], 200);
  EXPECT_NEAR(r.delay_p50[0], 0.003, 1e-12);
  EXPECT_EQ(r.steps, 200);
  EXPECT_GT(r.step_max, 0.0);
}
