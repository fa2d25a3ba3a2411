// The control pose (core::ControlPredictor through the engine, POSE_CONTROL of the daemon and of
// lcmloc-replay --control): it moves with the motion alone, jumps by no more than the canonical
// corrections made meanwhile, is the canonical state when no motion waits, and leaves the
// canonical output as it was.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>

#include "daemon/daemon.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/core/control_pose.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/input_order.hpp"
#include "lcmloc/drivers/scenario_map.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "lcmloc/simconfig/sim_config.hpp"
#include "process_fixture.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

class ControlPoseTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("lcmloc_control_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cfg_ = simconfig::loadSimSystemConfig(LCMLOC_PAPER_YAML);
    cfg_.scenario = replay::ovalScenario(cfg_.scenario, replay::OvalTrack{}, 30.0);
    cfg_.fusion.shadow.clear();
    cfg_.fusion.map_file = path("map.csv");
    drivers::writeScenarioMap(cfg_, cfg_.fusion.map_file);
    log_ = path("in.lcmlog");
    replay::writeSyntheticLog(cfg_.scenario, 30.0, log_, cfg_.channels);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  /// The log's inputs as the daemon's intake makes them, in the log's order.
  std::vector<core::EngineInput> inputs() {
    fusion::DaemonIntake intake(cfg_);
    std::vector<core::EngineInput> out;
    fusion::IntakeItem item;
    for (const auto& e : readLog(log_)) {
      const int n = static_cast<int>(e.data.size());
      if (e.channel == cfg_.channels.odometry) {
        lcmloc::odometry_t m;
        if (m.decode(e.data.data(), 0, n) < 0) continue;
        intake.take(e.channel, m, item);
      } else if (e.channel.rfind("MAGRULER", 0) == 0) {
        lcmloc::magruler_t m;
        if (m.decode(e.data.data(), 0, n) < 0) continue;
        intake.take(e.channel, m, item);
      } else {
        continue;
      }
      if (item.kind == fusion::IntakeItem::Kind::Input) out.push_back(item.input);
    }
    return out;
  }
  /// The control pose's jumps against the canonical corrections, the detections arriving late_us
  /// after their time.
  void checkJumps(int64_t late_us);
  fs::path dir_;
  simconfig::SimSystemConfig cfg_;
  std::string log_;
};

double angleDiff(double a, double b) { return std::remainder(a - b, 2.0 * M_PI); }

// A simulated run whose ruler detections arrive 30 ms late (inside the 50 ms window, so each one
// corrects the canonical state in the past, under motion already composed into the control
// pose): the control pose after each odometry message is the previous one moved by that message,
// plus no more than the corrections the canonical estimate made meanwhile, carried through the
// motion waiting (a heading correction swings the position by at most its angle times the
// distance waiting).
TEST_F(ControlPoseTest, NeverJumpsByMoreThanTheCanonicalCorrection) {
  ASSERT_EQ(app::engineConfig(cfg_).horizonUs(), 50000);
  checkJumps(30000);
}

// The same with the detections 200 ms late and a horizon widened for them to 0.25 s
// (fusion.sensors.magruler.delay): more motion waits under each correction, the bound holds.
TEST_F(ControlPoseTest, NeverJumpsByMoreThanTheCanonicalCorrectionWithinAWideHorizon) {
  cfg_.fusion.sensors["magruler"].delay = 0.25;
  ASSERT_EQ(app::engineConfig(cfg_).horizonUs(), 250000);
  checkJumps(200000);
}

void ControlPoseTest::checkJumps(int64_t late_us) {
  const auto all = inputs();
  const core::MarkerMap map = app::csv::loadMap(cfg_.fusion.map_file);
  core::EngineConfig ec = app::engineConfig(cfg_);
  // At most the increments of the horizon wait (100 Hz), plus the one pushed.
  const std::size_t max_waiting = static_cast<std::size_t>(ec.horizonUs() / 10000 + 1);

  core::FilterState active;  // the canonical state published last
  bool after_decision = false;
  double corr_xy = 0, corr_th = 0;  // corrections since the control pose before
  std::optional<core::FilterState> control_before;
  core::OdometryInput last_odo;
  std::vector<double> recent_ds;  // |delta_s| of the odometry pushed, newest last
  auto scratch = core::makeFilter(cfg_.fusion.filter, map);
  int controls = 0, corrected = 0, moved_by_correction = 0;
  double largest_jump = 0;

  core::EngineOutputs out;
  out.on_decision = [&](const std::string&, bool is_active, const core::GateDecision&) { after_decision = is_active; };
  out.on_state = [&](const std::string&, bool is_active, const core::FilterState& s) {
    if (!is_active) return;
    if (after_decision && active.x.size() >= 3) {
      corr_xy += std::hypot(s.x(0) - active.x(0), s.x(1) - active.x(1));
      corr_th += std::abs(angleDiff(s.x(2), active.x(2)));
    }
    after_decision = false;
    active = s;
  };
  out.on_control = [&](const core::FilterState& c) {
    ++controls;
    if (control_before) {
      scratch->initialize(*control_before);  // the control pose before, moved by this message
      scratch->predict(last_odo);
      const core::FilterState moved = scratch->state();
      double waiting = 0;
      for (std::size_t i = recent_ds.size() > max_waiting ? recent_ds.size() - max_waiting : 0; i < recent_ds.size(); ++i)
        waiting += recent_ds[i];
      const double jump_xy = std::hypot(c.x(0) - moved.x(0), c.x(1) - moved.x(1));
      const double jump_th = std::abs(angleDiff(c.x(2), moved.x(2)));
      EXPECT_LE(jump_xy, corr_xy + corr_th * waiting + 1e-9) << "control pose " << controls << " at " << c.utime;
      EXPECT_LE(jump_th, corr_th + 1e-12) << "control pose " << controls << " at " << c.utime;
      if (corr_xy + corr_th > 0) ++corrected;
      if (jump_xy > 1e-4) ++moved_by_correction;
      largest_jump = std::max(largest_jump, jump_xy);
    }
    control_before = c;
    corr_xy = corr_th = 0;
  };
  core::FusionEngine engine(ec, map, out);

  std::vector<core::EngineInput> late;  // detections waiting for their arrival, late_us after their time
  for (const auto& in : all) {
    if (!std::holds_alternative<core::OdometryInput>(in.payload)) {
      late.push_back(in);
      continue;
    }
    while (!late.empty() && late.front().utime + late_us <= in.utime) {
      engine.push(late.front());
      late.erase(late.begin());
    }
    last_odo = std::get<core::OdometryInput>(in.payload);
    recent_ds.push_back(std::abs(last_odo.delta_s));
    ASSERT_TRUE(engine.push(in));
  }
  EXPECT_EQ(engine.counters().too_old, 0);
  std::cout << controls << " control poses, " << corrected << " after corrections, " << moved_by_correction
            << " moved by them, the largest jump " << largest_jump << " m\n";
  EXPECT_GT(controls, 2000);
  EXPECT_GT(corrected, 15) << "the run corrects the canonical state under waiting motion";
  EXPECT_GT(moved_by_correction, 10) << "and those corrections reach the control pose";
  EXPECT_GT(largest_jump, 5e-3);
}

// No motion waiting: the control pose is the canonical state itself. A sample of a sensor the
// filter does not use (IMU for a ruler filter) makes no motion.
TEST_F(ControlPoseTest, EqualsTheCanonicalStateWhenNoMotionWaits) {
  const core::MarkerMap map = app::csv::loadMap(cfg_.fusion.map_file);
  auto active = core::makeFilter(cfg_.fusion.filter, map);
  core::OdometryInput u;
  u.utime = 10000;
  u.delta_s = 0.2;
  u.has_steering = true;
  u.steering = 0.05;
  active->predict(u);
  core::ControlPredictor predictor(std::make_shared<const core::MapIndex>(map));
  const core::FilterState canonical = active->state();
  const core::FilterState& none = predictor.pose(*active, cfg_.fusion.filter, 1, {});
  EXPECT_EQ(none.utime, canonical.utime);
  EXPECT_EQ(none.x, canonical.x);
  EXPECT_EQ(none.P, canonical.P);
  core::ImuInput imu;
  imu.utime = 20000;
  const core::EngineInput imu_in{"IMU", 1, imu.utime, imu};
  const core::FilterState& unused =
      predictor.pose(*active, cfg_.fusion.filter, 1, {{core::canonicalKey(imu_in), &imu_in}});
  EXPECT_EQ(unused.x, canonical.x);
  EXPECT_EQ(unused.utime, canonical.utime);
  // One increment waiting: moved by it, its covariance grown, stamped with its time.
  u.utime = 20000;
  const core::EngineInput odo_in{"ODOMETRY", 2, u.utime, u};
  const core::FilterState moved =
      predictor.pose(*active, cfg_.fusion.filter, 1, {{core::canonicalKey(odo_in), &odo_in}});
  EXPECT_EQ(moved.utime, 20000);
  EXPECT_NEAR(std::hypot(moved.x(0) - canonical.x(0), moved.x(1) - canonical.x(1)), 0.2, 0.01);
  EXPECT_GT((moved.P.topLeftCorner<3, 3>().trace()), (canonical.P.topLeftCorner<3, 3>().trace()));
  EXPECT_EQ(active->state().x, canonical.x) << "the canonical filter is not touched";
}

// Going on from the motion composed before (the same canonical state, more motion waiting after
// it) gives the numbers composing all of it again gives; a new canonical state, or motion
// waiting before what was composed (a late arrival), starts afresh.
TEST_F(ControlPoseTest, ComposingOnlyTheNewMotionEqualsComposingItAll) {
  const core::MarkerMap map = app::csv::loadMap(cfg_.fusion.map_file);
  const auto shared = std::make_shared<const core::MapIndex>(map);
  auto active = core::makeFilter(cfg_.fusion.filter, map);
  std::vector<core::EngineInput> in;
  for (int k = 0; k < 12; ++k) {
    core::OdometryInput u;
    u.utime = 10000 * (k + 1);
    u.delta_s = 0.1 + 0.01 * k;
    u.has_steering = true;
    u.steering = 0.02 * std::sin(k);
    in.push_back(core::EngineInput{"ODOMETRY", k, u.utime, u});
  }
  auto waiting = [&](std::vector<int> ks) {
    std::vector<core::ControlPredictor::Waiting> w;
    for (int k : ks) w.push_back({core::canonicalKey(in[k]), &in[k]});
    return w;
  };
  core::ControlPredictor going_on(shared);
  const std::vector<std::vector<int>> steps{{0}, {0, 1}, {0, 1, 2, 3}, {0, 2, 3}, {0, 1, 2, 3}, {1, 2, 3, 4}};
  const std::vector<int64_t> versions{1, 1, 1, 1, 1, 2};
  for (std::size_t s = 0; s < steps.size(); ++s) {
    if (s == 5) active->predict(std::get<core::OdometryInput>(in[0].payload));  // released: a new canonical state
    core::ControlPredictor fresh(shared);
    const core::FilterState expected = fresh.pose(*active, cfg_.fusion.filter, versions[s], waiting(steps[s]));
    const core::FilterState& got = going_on.pose(*active, cfg_.fusion.filter, versions[s], waiting(steps[s]));
    EXPECT_EQ(got.x, expected.x) << "step " << s;
    EXPECT_EQ(got.P, expected.P) << "step " << s;
    EXPECT_EQ(got.utime, expected.utime) << "step " << s;
  }
}

// Through the engine: the control pose is published for each odometry message as it is pushed,
// equals the canonical state once a far later IMU sample (which the active ruler filter does not
// compose, but a shadow uses, so that it moves the horizon) released everything, and the
// canonical outputs are the same with or without it.
TEST_F(ControlPoseTest, CanonicalOutputIsTheSameWithTheControlPose) {
  const auto all = inputs();
  const core::MarkerMap map = app::csv::loadMap(cfg_.fusion.map_file);
  auto run = [&](bool control) {
    std::vector<core::FilterState> states, controls;
    core::EngineOutputs out;
    out.on_state = [&](const std::string&, bool active, const core::FilterState& s) {
      if (active) states.push_back(s);
    };
    if (control) out.on_control = [&](const core::FilterState& s) { controls.push_back(s); };
    core::EngineConfig ecfg = app::engineConfig(cfg_);
    ecfg.shadow = {"odo_ins"};
    core::FusionEngine engine(ecfg, map, out);
    for (const auto& in : all) engine.push(in);
    core::ImuInput imu;  // 0.5 s after the last input: releases every one of them
    imu.utime = all.back().utime + 500000;
    engine.push(core::EngineInput{"IMU", 0, imu.utime, imu});
    return std::make_pair(states, controls);
  };
  const auto [with_states, controls] = run(true);
  const auto [without_states, none] = run(false);
  EXPECT_TRUE(none.empty());
  ASSERT_EQ(with_states.size(), without_states.size());
  for (std::size_t i = 0; i < with_states.size(); ++i) {
    ASSERT_EQ(with_states[i].x, without_states[i].x) << i;
    ASSERT_EQ(with_states[i].P, without_states[i].P) << i;
  }
  std::size_t odometry = 0;
  int64_t last_odometry = 0;
  for (const auto& in : all)
    if (std::holds_alternative<core::OdometryInput>(in.payload)) {
      ++odometry;
      last_odometry = in.utime;
    }
  ASSERT_EQ(controls.size(), odometry + 1);  // one per odometry message, and the IMU sample's
  EXPECT_EQ(controls.back().x, with_states.back().x);
  EXPECT_EQ(controls.back().P, with_states.back().P);
  EXPECT_EQ(controls[controls.size() - 2].utime, last_odometry) << "the newest motion, not yet released";
}

// An IMU sample no filter uses changes nothing in the control pose: none is published for it (it
// was, at the IMU's rate, the pose before it again). With a filter that uses the IMU, each one is.
TEST_F(ControlPoseTest, OnlyAnImuSampleSomeFilterUsesPublishesAControlPose) {
  const core::MarkerMap map = app::csv::loadMap(cfg_.fusion.map_file);
  for (const bool imu_shadow : {false, true}) {
    std::size_t controls = 0;
    core::EngineOutputs out;
    out.on_control = [&](const core::FilterState&) { ++controls; };
    core::EngineConfig ecfg = app::engineConfig(cfg_);
    if (imu_shadow) ecfg.shadow = {"odo_ins"};
    core::FusionEngine engine(ecfg, map, out);
    for (int k = 1; k <= 100; ++k) {
      core::OdometryInput u;
      u.utime = k * 10000;
      u.delta_s = 0.02;
      u.has_steering = true;
      engine.push(core::EngineInput{"ODOMETRY", k, u.utime, u});
      core::ImuInput imu;
      imu.utime = u.utime + 5000;
      imu.accel = core::Vec3(0, 0, 9.81);
      engine.push(core::EngineInput{"IMU", k, imu.utime, imu});
    }
    EXPECT_EQ(controls, imu_shadow ? 200u : 100u) << imu_shadow;
  }
}

}  // namespace
