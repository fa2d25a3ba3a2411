// Odometry/INS over real processes: lcmloc-ins-sim publishes GROUND_TRUTH, IMU and ODOMETRY,
// lcmloc-fusion runs odo_ins and publishes POSE; a VISION message (three landmark bearings)
// re-initializes the filter; a NaN IMU sample is refused with a status event.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "process_fixture.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"
#include "lcmloc/pose_t.hpp"

using namespace std::chrono_literals;

namespace {

bool waitFor(lcmloc::bus::Bus& bus, const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!pred() && std::chrono::steady_clock::now() < deadline) bus.handle(50);
  return pred();
}

class InsProcess : public ProcessFixture {};

}  // namespace

TEST_F(InsProcess, FusionRunsOdoInsOnImuAndOdometryAndTakesALandmarkFix) {
  lcmloc::bus::Bus bus(url_);
  std::vector<lcmloc::pose_t> poses;
  std::vector<lcmloc::ground_truth_t> truth;
  std::vector<lcmloc::gate_decision_t> decisions;
  std::vector<lcmloc::fusion_status_t> status;
  bus.subscribe<lcmloc::pose_t>("POSE", [&](const std::string&, const lcmloc::pose_t& m, int64_t) { poses.push_back(m); });
  bus.subscribe<lcmloc::ground_truth_t>(
      "GROUND_TRUTH", [&](const std::string&, const lcmloc::ground_truth_t& m, int64_t) { truth.push_back(m); });
  bus.subscribe<lcmloc::gate_decision_t>(
      "GATE", [&](const std::string&, const lcmloc::gate_decision_t& m, int64_t) { decisions.push_back(m); });
  bus.subscribe<lcmloc::fusion_status_t>(
      "FUSION_STATUS", [&](const std::string&, const lcmloc::fusion_status_t& m, int64_t) { status.push_back(m); });

  Child fusion(LCMLOC_FUSION, {"--config", LCMLOC_INS_YAML, "--lcm-url", url_}, path("fusion.log"));
  ASSERT_TRUE(waitFor(bus, [&] { return !status.empty(); }, 10s)) << fusion.output();
  Child sim(LCMLOC_INS_SIM,
            {"--config", LCMLOC_INS_YAML, "--lcm-url", url_, "--duration", "20", "--realtime-factor", "4"},
            path("sim.log"));
  // Run to the end of the simulation while receiving.
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  std::optional<int> rc;
  while (!(rc = sim.wait(0ms)) && std::chrono::steady_clock::now() < deadline) bus.handle(50);
  ASSERT_EQ(rc.value_or(-1), 0) << sim.output();
  waitFor(bus, [&] { return false; }, 300ms);
  ASSERT_GT(truth.size(), 1500u) << sim.output();
  ASSERT_GT(poses.size(), 1000u) << fusion.output();
  EXPECT_EQ(poses.back().filter, "odo_ins");
  // Compare the last pose with the truth at its time: the vehicle has travelled ~100 m.
  const auto& p = poses.back();
  const lcmloc::ground_truth_t* t = nullptr;
  for (const auto& g : truth)
    if (g.utime == p.utime) t = &g;
  ASSERT_NE(t, nullptr);
  EXPECT_GT(t->distance, 50.0);
  EXPECT_LT(std::hypot(p.state[0] - t->x, p.state[1] - t->y), 0.5);
  ASSERT_EQ(p.state.size(), 11u);  // x, y, theta, odo_scale_error, velocity, biases
  EXPECT_EQ(p.state_names[4], "v_east");
  EXPECT_NEAR(std::hypot(p.state[4], p.state[5]), t->speed, 0.1);

  // NaN IMU sample: refused by the daemon with a status event, the daemon keeps running.
  lcmloc::imu_t bad{};
  bad.utime = p.utime + 100000;
  bad.seq = 1000000;
  bad.accel[0] = NAN;
  bus.publish("IMU", bad);
  ASSERT_TRUE(waitFor(bus, [&] {
    for (const auto& s : status)
      if (s.event == "rejected_input" && s.detail.find("IMU") != std::string::npos) return true;
    return false;
  }, 5s)) << fusion.output();

  // Three-landmark fixes (landmarks of config/ins_paper.yaml) from a pose 40 m off the filter's:
  // the gate (fusion.landmark_fix) refuses the first two, the lock-out takes the third.
  const double lm[3][2] = {{0.0, 577.35}, {-500.0, -288.68}, {500.0, -288.68}};
  const double fx = p.state[0] + 30.0, fy = p.state[1] - 25.0, fth = p.state[2] + 0.01;
  for (int k = 0; k < 4; ++k) {  // the fourth pushes the third out of the reorder window
    lcmloc::landmark_bearings_t b;
    b.utime = p.utime + 1000000 + k * 1000000;
    b.seq = k;
    b.count = 3;
    for (int i = 0; i < 3; ++i) {
      b.landmark_ids.push_back(i + 1);
      b.bearings.push_back(std::remainder(std::atan2(lm[i][1] - fy, lm[i][0] - fx) - fth, 2 * M_PI));
    }
    b.bearing_std = 30.0 / 3600.0 * M_PI / 180.0;
    bus.publish("VISION", b);
  }
  ASSERT_TRUE(waitFor(bus, [&] {
    for (const auto& d : decisions)
      if (d.reason == "fix_lockout") return true;
    return false;
  }, 5s)) << fusion.output();
  std::vector<std::string> reasons;
  for (const auto& d : decisions)
    if (d.sensor == "VISION" && std::string(d.filter) == "odo_ins") reasons.push_back(d.reason + (d.accepted ? "+" : "-"));
  EXPECT_EQ(reasons, (std::vector<std::string>{"gate-", "gate-", "fix_lockout+"}));
  const int64_t t_fix = p.utime + 3000000;
  ASSERT_TRUE(waitFor(bus, [&] { return poses.back().utime >= t_fix; }, 5s));
  const lcmloc::pose_t* after = nullptr;
  for (const auto& q : poses)
    if (q.utime == t_fix) after = &q;
  ASSERT_NE(after, nullptr);
  // Standing still after the fix: the pose is where the fix put it.
  EXPECT_NEAR(after->state[0], fx, 0.05);
  EXPECT_NEAR(after->state[1], fy, 0.05);
  EXPECT_NEAR(std::remainder(after->state[2] - fth, 2 * M_PI), 0.0, 1e-4);
  fusion.signal(SIGINT);
  EXPECT_EQ(fusion.wait(5s).value_or(-1), 0) << fusion.output();
}

TEST_F(InsProcess, InsSimHelpAndBadConfig) {
  Child help(LCMLOC_INS_SIM, {"--help"}, path("help.log"));
  EXPECT_EQ(help.wait(5s).value_or(-1), 0);
  EXPECT_NE(help.output().find("--config"), std::string::npos);
  const std::string bad = writeFile("bad.yaml", "ins_sim: {start: sideways}\n");
  Child b(LCMLOC_INS_SIM, {"--config", bad, "--lcm-url", url_}, path("bad.log"));
  EXPECT_EQ(b.wait(5s).value_or(-1), 2) << b.output();
  EXPECT_NE(b.output().find("ins_sim.start"), std::string::npos) << b.output();
  const std::string bad2 = writeFile("bad2.yaml", "fusion: {landmarks: [{id: 1, x: 0.0}]}\n");
  Child c(LCMLOC_FUSION, {"--config", bad2, "--lcm-url", url_}, path("bad2.log"));
  EXPECT_EQ(c.wait(5s).value_or(-1), 2) << c.output();
  EXPECT_NE(c.output().find("fusion.landmarks[0]"), std::string::npos) << c.output();
}
