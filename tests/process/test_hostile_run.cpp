// lcmloc-hostile-run, short: the default system under lcmloc-launcher with a second publisher
// sending each kind of bad message on every input channel (against a clean run of the same), and
// a 20 s soak with 1 % of the input messages corrupted. The bounds are read back from the
// report: RMSE within 2x of the clean run, POSE never a step longer than twice its period in
// message time, no NaN, the second publisher named on each channel the system publishes on.
// (Wall-clock silences and RSS are reported by the command, not asserted: they depend on the
// machine's load.)
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include <nlohmann/json.hpp>

#include "process_fixture.hpp"

namespace {

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

int run(const std::string& args, const std::string& out) {
  const int st = std::system((std::string(LCMLOC_HOSTILE_RUN) + " " + args + " > " + out + " 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

}  // namespace

class HostileRun : public ProcessFixture {};

TEST_F(HostileRun, ASecondPublisherOnEveryInputChannelOfTheRunningSystem) {
  const int rc = run("--lcm-url '" + url_ + "' --factor 2 hostile -o " + path("out"), path("run.txt"));
  const auto j = readJson(path("out/report.json"));
  ASSERT_TRUE(j.is_object()) << rc << "\n" << std::ifstream(path("run.txt")).rdbuf();
  const auto& clean = j["clean"];
  const auto& hostile = j["hostile"];
  EXPECT_GT(clean["scored"].get<int>(), 1000);
  EXPECT_GT(hostile["scored"].get<int>(), 1000);
  EXPECT_LE(hostile["rmse_m"].get<double>(), 2 * clean["rmse_m"].get<double>());
  EXPECT_EQ(hostile["non_finite_poses"].get<int>(), 0);
  EXPECT_LE(hostile["longest_pose_step_message_time_s"].get<double>(), 2 * hostile["pose_period_s"].get<double>());
  EXPECT_EQ(hostile["daemon_processes"].get<int>(), 1);
  // Every input channel was sent to, and each channel the system itself publishes on had its
  // second publisher named on the status.
  for (const char* ch : {"ODOMETRY", "MAGRULER", "MAGRULER_FAULT", "IMU", "GPS", "LANDMARKS", "BEACONS", "VISION",
                         "FUSION_CONTROL"})
    EXPECT_GT(hostile["sent_per_channel"].value(ch, 0), 0) << ch;
  for (const char* ch : {"ODOMETRY", "MAGRULER"}) {
    ASSERT_TRUE(j["second_publisher_named"].contains(ch)) << j["second_publisher_named"].dump();
    EXPECT_NE(j["second_publisher_named"][ch].dump().find("second publisher"), std::string::npos)
        << ch << ": " << j["second_publisher_named"][ch].dump();
  }
  EXPECT_EQ(rc, 0) << std::ifstream(path("run.txt")).rdbuf();
}

TEST_F(HostileRun, ASoakWithOnePercentOfTheInputMessagesCorrupted) {
  const int rc = run("--lcm-url '" + url_ + "' --seed 7 soak --duration 20 -o " + path("soak"), path("soak.txt"));
  const auto j = readJson(path("soak/report.json"));
  ASSERT_TRUE(j.is_object()) << rc << "\n" << std::ifstream(path("soak.txt")).rdbuf();
  const auto& r = j["run"];
  EXPECT_GT(r["poses"].get<int>(), 1000);
  EXPECT_GT(r["disturbing_messages_sent"].get<int>(), 5) << "1 % of some 2,000 input messages a second is corrupted";
  EXPECT_EQ(r["non_finite_poses"].get<int>(), 0);
  EXPECT_EQ(r["pose_steps_over_2_periods"].get<int>(), 0);
  EXPECT_EQ(r["daemon_processes"].get<int>(), 1);
  EXPECT_GT(j["rss_kb"]["samples"].size(), 10u);
  EXPECT_EQ(rc, 0) << std::ifstream(path("soak.txt")).rdbuf();
}
