// The `vision` section and the top-level `landmarks` map of the system YAML.
#include <gtest/gtest.h>

#include <string>

#include "lcmloc/app/config.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

namespace {
std::string errorOf(const std::string& yaml) {
  try {
    simconfig::parseSimSystemConfig(yaml, "t.yaml");
  } catch (const app::ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(VisionConfig, SectionAndLandmarkMapParsed) {
  const auto cfg = simconfig::parseSimSystemConfig(R"(
vision: {rate_hz: 5, bearing_std: 2.0e-4, resolution: 0, seed: 17, max_range: 800}
landmarks:
  - {id: 3, x: 10.5, y: -20}
  - {id: 1, x: -1.0e3, y: 4}
channels: {vision: CAMERA}
)",
                                             "t.yaml");
  const auto& v = cfg.scenario.vision;
  EXPECT_EQ(v.rate_hz, 5.0);
  EXPECT_EQ(v.bearing_std, 2.0e-4);
  EXPECT_EQ(v.resolution, 0.0);
  EXPECT_EQ(v.seed, 17u);
  EXPECT_EQ(v.max_range, 800.0);
  ASSERT_EQ(cfg.scenario.landmarks.size(), 2u);
  EXPECT_EQ(cfg.scenario.landmarks[0].id, 3);  // file order kept
  EXPECT_EQ(cfg.scenario.landmarks[0].x, 10.5);
  EXPECT_EQ(cfg.scenario.landmarks[0].y, -20.0);
  EXPECT_EQ(cfg.scenario.landmarks[1].id, 1);
  EXPECT_EQ(cfg.scenario.landmarks[1].x, -1000.0);
  EXPECT_EQ(cfg.channels.vision, "CAMERA");
  // Defaults: the paper's sensor (30", 14"), no map.
  const auto d = simconfig::parseSimSystemConfig("{}", "t.yaml");
  EXPECT_NEAR(d.scenario.vision.bearing_std * 206264.806, 30.0, 1e-6);
  EXPECT_NEAR(d.scenario.vision.resolution * 206264.806, 14.0, 1e-6);
  EXPECT_TRUE(d.scenario.landmarks.empty());
  EXPECT_EQ(d.channels.vision, "VISION");
}

TEST(VisionConfig, BadLandmarkMapRefusedWithFileAndKey) {
  std::string e = errorOf("landmarks: [{id: 1, x: 0, y: 0}, {id: 2, x: 5, y: 5}, {id: 1, x: 9, y: 9}]\n");
  EXPECT_NE(e.find("t.yaml: landmarks[2].id: duplicate landmark id 1 (also landmarks[0])"), std::string::npos) << e;
  e = errorOf("landmarks: [{id: 1, x: .nan, y: 0}]\n");
  EXPECT_NE(e.find("t.yaml: landmarks[0].x: expected a finite number"), std::string::npos) << e;
  e = errorOf("landmarks: [{id: 1, x: 0, y: .inf}]\n");
  EXPECT_NE(e.find("landmarks[0].y: expected a finite number"), std::string::npos) << e;
  e = errorOf("landmarks: [{x: 0, y: 0}]\n");
  EXPECT_NE(e.find("landmarks[0].id: missing"), std::string::npos) << e;
  e = errorOf("landmarks: [{id: 1, x: 0}]\n");
  EXPECT_NE(e.find("landmarks[0]: missing x or y"), std::string::npos) << e;
  e = errorOf("landmarks: [{id: 1, x: 0, y: 0, z: 3}]\n");
  EXPECT_NE(e.find("landmarks[0].z: unknown key"), std::string::npos) << e;
  e = errorOf("landmarks: [{id: 1.5, x: 0, y: 0}]\n");
  EXPECT_NE(e.find("landmarks[0].id: expected an integer"), std::string::npos) << e;
  e = errorOf("landmarks: {id: 1, x: 0, y: 0}\n");
  EXPECT_NE(e.find("landmarks: expected a list of {id, x, y}"), std::string::npos) << e;
  e = errorOf("vision: {bearing_std: -1}\n");
  EXPECT_NE(e.find("vision.bearing_std: value -1 out of range"), std::string::npos) << e;
  e = errorOf("vision: {fov: 1}\n");
  EXPECT_NE(e.find("vision.fov: unknown key"), std::string::npos) << e;
}
