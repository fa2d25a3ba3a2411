// The running daemon's wall-clock timing as lcmloc-ctl status prints it, and lcmloc-latency-bench
// over real processes: a short run gives a well-formed report (no time is asserted).
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include <yaml-cpp/yaml.h>

#include "lcmloc/odometry_t.hpp"
#include "process_fixture.hpp"

using namespace std::chrono_literals;

class LatencyProcessTest : public ProcessFixture {};

// 1.5 s of 100 Hz ODOMETRY into a running daemon: lcmloc-ctl status prints its status and the
// timing table with the ODOMETRY channel and the per-step processing time.
TEST_F(LatencyProcessTest, CtlStatusPrintsTheDaemonsTiming) {
  Child daemon(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML}, path("fusion.out"));
  lcm::LCM lcm(url_);
  ASSERT_TRUE(lcm.good());
  Child ctl(LCMLOC_CTL, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--timeout", "10", "status"},
            path("ctl.out"));
  const int64_t t0 = std::chrono::duration_cast<std::chrono::microseconds>(
                         std::chrono::system_clock::now().time_since_epoch()).count();
  std::optional<int> rc;
  for (int k = 0; k < 1000 && !(rc = ctl.wait(0ms)); ++k) {
    lcmloc::odometry_t m{};
    m.utime = t0 + k * 10000;
    m.seq = k;
    m.delta_s = 0.1;
    m.has_steering = true;
    lcm.publish("ODOMETRY", &m);
    std::this_thread::sleep_for(10ms);
  }
  if (!rc) rc = ctl.wait(10s);
  ASSERT_EQ(rc.value_or(-1), 0) << ctl.output() << daemon.output();
  const std::string out = ctl.output();
  EXPECT_NE(out.find("filter ukf_gated"), std::string::npos) << out;
  EXPECT_NE(out.find("delay p50 ms"), std::string::npos) << out;
  EXPECT_NE(out.find("ODOMETRY"), std::string::npos) << out;
  EXPECT_NE(out.find("filter step"), std::string::npos) << out;
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(10s).value_or(-1), 0) << daemon.output();
}

// A one-second run: the report names every figure, with latencies of each output measured.
TEST_F(LatencyProcessTest, TheBenchmarkWritesAWellFormedReport) {
  Child bench(LCMLOC_LATENCY_BENCH,
              {"--url", url_, "--config", LCMLOC_PAPER_YAML, "--fusion", LCMLOC_FUSION,
               "--duration", "1", "--warmup", "0.5", "-o", path("report.json")},
              path("bench.out"));
  ASSERT_EQ(bench.wait(60s).value_or(-1), 0) << bench.output();
  const YAML::Node r = YAML::LoadFile(path("report.json"));  // (JSON is YAML)
  for (const char* k : {"relay", "control", "canonical"}) {
    ASSERT_TRUE(r[k]) << k;
    EXPECT_GT(r[k]["n"].as<int>(), 10) << k;
    EXPECT_LE(r[k]["p50_ms"].as<double>(), r[k]["p99_ms"].as<double>()) << k;
    EXPECT_LE(r[k]["p99_ms"].as<double>(), r[k]["max_ms"].as<double>()) << k;
  }
  // A control pose per ODOMETRY message (the relay's probe has its rate, 100 Hz), none per IMU
  // sample: ukf_gated does not use the IMU (there would be twice as many).
  EXPECT_NEAR(r["control"]["n"].as<int>(), r["relay"]["n"].as<int>(), 10);
  EXPECT_GE(r["cpu"]["daemon_s"].as<double>(), 0.0);
  EXPECT_GT(r["rss_kb"]["peak"].as<int>(), 0);
  EXPECT_GE(r["rss_kb"]["peak"].as<int>(), r["rss_kb"]["last"].as<int>());
  EXPECT_NE(bench.output().find("control pose (POSE_CONTROL)"), std::string::npos) << bench.output();
}
