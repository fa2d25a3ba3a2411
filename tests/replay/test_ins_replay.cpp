// Offline replay of an odometry/INS sensor log with a VISION message: lcmloc's replay runs the
// daemon's code, so odo_ins consumes IMU + ODOMETRY and the landmark fix re-initializes it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/common/config.hpp"
#include "lcmloc/common/convert.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/models/ins_sim.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "test_log_writer.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

TEST(InsReplay, OdoInsAndLandmarkFixFromALog) {
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_ins_replay_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string in = (dir / "in.lcmlog").string(), out = (dir / "out.lcmlog").string();
  auto cfg = common::parseSystemConfig(
      "fusion:\n  filter: {type: odo_ins}\n  landmarks:\n"
      "    - {id: 1, x: 0.0, y: 577.35}\n    - {id: 2, x: -500.0, y: -288.68}\n    - {id: 3, x: 500.0, y: -288.68}\n",
      "test.yaml");
  models::InsSimConfig sc;
  sc.duration = 4.0;  // standing 2 s, then the hard start
  models::InsSim sim(sc, 1000000);
  int64_t last = 0, seq = 0;
  {
    testlog::LogWriter log(in);
    while (!sim.finished()) {
      const auto s = sim.step();
      if (s.odometry) log.add("ODOMETRY", common::toLcm(*s.odometry, seq), s.odometry->input.utime);
      if (s.imu) log.add("IMU", common::toLcm(*s.imu, seq), s.imu->utime);
      ++seq;
      last = s.truth.utime;
    }
    // Bearings from (40, -30) heading north-west, twice (the second ends the reorder window).
    const double lm[3][2] = {{0.0, 577.35}, {-500.0, -288.68}, {500.0, -288.68}};
    for (int k = 0; k < 2; ++k) {
      lcmloc::landmark_bearings_t b;
      b.utime = last + 500000 + k * 500000;
      b.seq = k;
      b.count = 3;
      for (int i = 0; i < 3; ++i) {
        b.landmark_ids.push_back(i + 1);
        b.bearings.push_back(std::remainder(std::atan2(lm[i][1] + 30.0, lm[i][0] - 40.0) - 2.3, 2 * M_PI));
      }
      b.bearing_std = 30.0 / 3600.0 * M_PI / 180.0;
      log.add("VISION", b, b.utime);
    }
  }
  replay::ReplayOptions o;
  o.input = in;
  o.output = out;
  o.progress_period_s = 0;
  const auto r = replay::replayLog(cfg, o);
  EXPECT_EQ(r.rejected, 0);
  int fixes = 0, poses = 0;
  lcmloc::pose_t first_after_fix;
  bool have_after = false;
  lcm::LogFile log(out, "r");
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == "GATE") {
      lcmloc::gate_decision_t d;
      ASSERT_GE(d.decode(ev->data, 0, ev->datalen), 0);
      if (d.reason == "fix") {
        ++fixes;
        EXPECT_TRUE(d.accepted);
      }
    } else if (ev->channel == "POSE") {
      lcmloc::pose_t p;
      ASSERT_GE(p.decode(ev->data, 0, ev->datalen), 0);
      ++poses;
      EXPECT_EQ(p.filter, "odo_ins");
      if (!have_after && p.utime == last + 500000) {
        first_after_fix = p;
        have_after = true;
      }
    }
  }
  EXPECT_GT(poses, 300);
  EXPECT_EQ(fixes, 2);
  ASSERT_TRUE(have_after);
  EXPECT_NEAR(first_after_fix.state[0], 40.0, 1e-3);
  EXPECT_NEAR(first_after_fix.state[1], -30.0, 1e-3);
  EXPECT_NEAR(first_after_fix.state[2], 2.3, 1e-6);
  fs::remove_all(dir);
}
