// Offline replay of an odometry/INS sensor log with a VISION message: lcmloc's replay runs the
// daemon's code, so odo_ins consumes IMU + ODOMETRY and the landmark fix re-initializes it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/sim/ins_sim.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "test_log_writer.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

TEST(InsReplay, OdoInsAndLandmarkFixFromALog) {
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_ins_replay_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string in = (dir / "in.lcmlog").string(), out = (dir / "out.lcmlog").string();
  auto cfg = app::parseSystemConfig(
      "fusion:\n  filter: {type: odo_ins}\n  landmarks:\n"
      "    - {id: 1, x: 0.0, y: 577.35}\n    - {id: 2, x: -500.0, y: -288.68}\n    - {id: 3, x: 500.0, y: -288.68}\n"
      "  landmark_fix: {gate_probability: 0}\n",  // a fix 50 m off is taken (no gate)
      "test.yaml");
  sim::InsSimConfig sc;
  sc.duration = 4.0;  // standing 2 s, then the hard start
  sim::InsSim sim(sc, 1000000);
  int64_t last = 0, seq = 0;
  {
    testlog::LogWriter log(in);
    while (!sim.finished()) {
      const auto s = sim.step();
      if (s.odometry) log.add("ODOMETRY", drivers::toLcm(*s.odometry, seq), s.odometry->input.utime);
      if (s.imu) log.add("IMU", drivers::toLcm(*s.imu, seq), s.imu->utime);
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


// A hot swap from dead_reckoning to odo_ins at 12 m/s on the §II route (a control message
// through the engine, as lcmloc-ctl sends it): the new filter drives on from the handed-over
// pose. Before odo_ins took an unknown velocity as 0 m/s (0.01 m/s sure) and ran up to 230 m off
// within 40 s of the switch.
TEST(InsReplay, SwitchFromDeadReckoningToOdoInsAtSpeedDrivesOn) {
  sim::InsSimConfig sc;
  sc.duration = 120.0;
  sim::InsSim sim(sc, 1000000);
  core::EngineConfig ec;
  ec.filter.type = "dead_reckoning";
  ec.filter.ins.latitude = sc.latitude;
  ec.filter.ins.longitude = sc.longitude;
  ec.filter.initial_pose = core::Vec3(0, 0, sc.heading);
  ec.reorder_window_us = 0;
  core::FilterState last;
  std::string active;
  core::EngineOutputs out;
  out.on_state = [&](const std::string& f, bool is_active, const core::FilterState& s) {
    if (!is_active) return;
    last = s;
    active = f;
  };
  core::FusionEngine engine(ec, {}, out);
  int64_t seq = 0;
  double at_switch = -1, worst = 0, speed = 0, truth_speed = 0;
  while (!sim.finished()) {
    const auto st = sim.step();
    const double t = (st.truth.utime - 1000000) * 1e-6;
    truth_speed = st.truth.speed;
    if (at_switch < 0 && t >= 60.0) {
      core::SwitchFilter sw{ec.filter};
      sw.config.type = "odo_ins";
      engine.push(core::EngineInput{"FUSION_CONTROL", seq++, st.truth.utime, core::ControlCommand(sw)});
    }
    if (st.odometry) engine.push(core::EngineInput{"ODOMETRY", seq++, st.odometry->input.utime, st.odometry->input});
    if (st.imu) {
      engine.push(core::EngineInput{"IMU", seq, st.imu->utime, st.imu->input("IMU", seq)});
      ++seq;
    }
    engine.flush();
    const double err = std::hypot(last.x[0] - st.truth.x, last.x[1] - st.truth.y);
    if (at_switch < 0 && active == "odo_ins") {
      at_switch = err;
      speed = st.truth.speed;
    } else if (at_switch >= 0) {
      worst = std::max(worst, std::abs(err - at_switch));
    }
  }
  ASSERT_EQ(active, "odo_ins");
  EXPECT_GT(speed, 10.0);
  EXPECT_GT(at_switch, 1.0);  // dead reckoning's error, carried over
  EXPECT_LT(worst, 2.0) << "error at the switch " << at_switch << " m";
  EXPECT_NEAR(std::hypot(last.x[4], last.x[5]), truth_speed, 0.1);
}
