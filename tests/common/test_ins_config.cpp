// Config sections and conversions of the odometry/INS/vision method: ins_sim, fusion.filter.ins,
// fusion.landmarks, channels.vision, landmark_bearings_t -> BearingsInput.
#include <gtest/gtest.h>

#include <cmath>

#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/convert.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

TEST(InsConfig, PaperFileLoads) {
  const auto cfg = simconfig::loadSimSystemConfig(LCMLOC_INS_YAML);
  EXPECT_EQ(cfg.fusion.filter.type, "odo_ins");
  EXPECT_EQ(cfg.fusion.shadow, std::vector<std::string>{"odo_ins_uncal"});
  EXPECT_DOUBLE_EQ(cfg.fusion.filter.ins.odo_markov, 0.001);
  EXPECT_DOUBLE_EQ(cfg.fusion.filter.ins.latitude, 40.0);
  EXPECT_EQ(cfg.ins_sim.start, "hard");
  EXPECT_DOUBLE_EQ(cfg.ins_sim.duration, 3600.0);
  ASSERT_EQ(cfg.fusion.landmarks.size(), 3u);
  EXPECT_DOUBLE_EQ(cfg.fusion.landmarks.at(2).x(), -500.0);
  EXPECT_EQ(cfg.channels.vision, "VISION");
  EXPECT_DOUBLE_EQ(cfg.fusion.fix_gate.probability, 0.9999);
  EXPECT_EQ(cfg.fusion.fix_gate.lockout_rejections, 2);
  EXPECT_DOUBLE_EQ(cfg.fusion.fix.max_condition, 100.0);
  // The paper's vision run re-initializes with every fix (no gate).
  EXPECT_DOUBLE_EQ(simconfig::loadSimSystemConfig(LCMLOC_INS_VISION_YAML).fusion.fix_gate.probability, 0.0);
  const auto set = simconfig::parseSimSystemConfig(
      "fusion: {landmark_fix: {gate_probability: 0.99, lockout_rejections: 0, max_condition: 1000}}\n", "t.yaml");
  EXPECT_DOUBLE_EQ(set.fusion.fix_gate.probability, 0.99);
  EXPECT_EQ(set.fusion.fix_gate.lockout_rejections, 0);
  EXPECT_DOUBLE_EQ(set.fusion.fix.max_condition, 1000.0);
}

TEST(InsConfig, ErrorsNameTheKey) {
  auto expectError = [](const std::string& yaml, const std::string& key) {
    try {
      simconfig::parseSimSystemConfig(yaml, "t.yaml");
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const app::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  expectError("fusion: {filter: {ins: {gyro_drift: 1}}}\n", "fusion.filter.ins");
  expectError("fusion: {filter: {ins: {max_imu_gap: 0}}}\n", "fusion.filter.ins.max_imu_gap");
  expectError("fusion: {landmarks: [{id: 1, x: 0, y: 0}, {id: 1, x: 5, y: 5}]}\n", "fusion.landmarks[1].id");
  expectError("fusion: {landmarks: {id: 1}}\n", "fusion.landmarks");
  expectError("fusion: {landmark_fix: {gate_probability: 1}}\n", "fusion.landmark_fix.gate_probability");
  expectError("fusion: {landmark_fix: {gate: 0.99}}\n", "fusion.landmark_fix");
  expectError("fusion: {landmark_fix: {lockout_rejections: -1}}\n", "fusion.landmark_fix.lockout_rejections");
  expectError("fusion: {landmark_fix: {max_condition: 0.5}}\n", "fusion.landmark_fix.max_condition");
  expectError("ins_sim: {profile: custom}\n", "ins_sim.segments");
  expectError("ins_sim: {segments: [{duration: 1, accel: 0, yawrate: 1}]}\n", "ins_sim.segments[0]");
  expectError("ins_sim: {imu_dropouts: [{start: -1, duration: 1}]}\n", "ins_sim.imu_dropouts[0].start");
}

TEST(InsConvert, BearingsValidated) {
  lcmloc::landmark_bearings_t m;
  m.utime = 10;
  m.seq = 3;
  m.count = 2;
  m.landmark_ids = {4, 5};
  m.bearings = {0.1, -0.2};
  m.bearing_std = 1e-4;
  std::string why;
  auto b = bus::toCore(m, "VISION", &why);
  ASSERT_TRUE(b.has_value()) << why;
  EXPECT_EQ(b->ids, (std::vector<int>{4, 5}));
  EXPECT_EQ(b->bearings, (std::vector<double>{0.1, -0.2}));
  EXPECT_EQ(b->sensor, "VISION");
  m.count = 3;
  EXPECT_FALSE(bus::toCore(m, "VISION", &why).has_value());
  EXPECT_NE(why.find("count"), std::string::npos);
  m.count = 2;
  m.bearings[1] = NAN;
  EXPECT_FALSE(bus::toCore(m, "VISION", &why).has_value());
  EXPECT_NE(why.find("NaN"), std::string::npos);
}
