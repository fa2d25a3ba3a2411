// Every kind of bad message on every input channel of a running lcmloc-fusion over real LCM
// (udpm, ttl=0): each counted under its channel and reason on the stop status and dropped, the
// pose finite, and POSE at the odometry's rate in message time.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "hostile_messages.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "process_fixture.hpp"

using namespace std::chrono_literals;
using namespace lcmloc::hostile;

class HostileProcess : public ProcessFixture {};

TEST_F(HostileProcess, EveryKindOfBadMessageOnEveryInputChannelOfARunningDaemon) {
  const lcmloc::app::SystemConfig cfg = lcmloc::app::loadSystemConfig(LCMLOC_PAPER_YAML);
  lcm::LCM lcm(url_);
  ASSERT_TRUE(lcm.good());
  std::mutex mu;
  std::vector<lcmloc::pose_t> poses;
  std::vector<lcmloc::fusion_status_t> status;
  struct Sink {
    std::mutex* mu;
    std::vector<lcmloc::pose_t>* poses;
    std::vector<lcmloc::fusion_status_t>* status;
    void pose(const lcm::ReceiveBuffer*, const std::string&, const lcmloc::pose_t* m) {
      std::lock_guard<std::mutex> l(*mu);
      poses->push_back(*m);
    }
    void st(const lcm::ReceiveBuffer*, const std::string&, const lcmloc::fusion_status_t* m) {
      std::lock_guard<std::mutex> l(*mu);
      status->push_back(*m);
    }
  } sink{&mu, &poses, &status};
  lcm.subscribe(cfg.channels.pose, &Sink::pose, &sink);
  lcm.subscribe(cfg.channels.status, &Sink::st, &sink);
  std::atomic<bool> stop{false};
  std::thread rx([&] {
    while (!stop) lcm.handleTimeout(20);
  });
  struct Join {  // (a failed ASSERT returns early: the thread is joined, not left to terminate())
    std::atomic<bool>& stop;
    std::thread& t;
    ~Join() {
      stop = true;
      if (t.joinable()) t.join();
    }
  } join{stop, rx};
  // The daemon starts once this side listens: its "started" status is published once.
  Child daemon(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML}, path("fusion.out"));
  // Wait for the daemon to listen (its "started" status; slow on a loaded machine).
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  auto started = [&] {
    std::lock_guard<std::mutex> l(mu);
    for (const auto& s : status)
      if (s.event == "started") return true;
    return false;
  };
  while (!started() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(started()) << daemon.output();

  const int64_t t0 = 1'000'000;
  const int64_t step = 10'000;
  int64_t k = 0;
  auto odo = [&](int n) {
    for (int i = 0; i < n; ++i, ++k) {
      const auto m = odometry(k, t0 + k * step);
      lcm.publish(cfg.channels.odometry, &m);
      std::this_thread::sleep_for(1ms);
    }
  };
  odo(100);
  std::map<std::string, int64_t> seq;
  const auto all = kinds(cfg.channels);
  for (const auto& bad : badKinds())
    for (const auto& kind : all) {
      const bool odometry_channel = kind.channel == cfg.channels.odometry;
      const int64_t t = odometry_channel ? t0 + k * step : t0 + k * step + 5000;
      const int64_t s = odometry_channel ? k++ : seq[kind.channel]++;
      const std::vector<uint8_t> bytes = badMessage(kind, bad, s, t);
      for (int c = 0; c < (bad == "flood" ? 100 : 1); ++c) {
        lcm.publish(kind.channel, bytes.data(), static_cast<unsigned>(bytes.size()));
        if (c % 20 == 19) std::this_thread::sleep_for(1ms);
      }
      odo(10);
    }
  odo(300);
  // Everything sent is taken in before the stop (a slow daemon, e.g. under the sanitizers): the
  // pose of an odometry message sent last but for the reorder window's has come.
  const int64_t last = t0 + (k - 10) * step;
  auto caught_up = [&] {
    std::lock_guard<std::mutex> l(mu);
    return !poses.empty() && poses.back().utime >= last;
  };
  const auto until = std::chrono::steady_clock::now() + 20s;
  while (!caught_up() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(caught_up()) << daemon.output();
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(10s).value_or(-1), 0) << daemon.output();
  std::this_thread::sleep_for(200ms);
  stop = true;
  rx.join();

  std::lock_guard<std::mutex> l(mu);
  ASSERT_GT(poses.size(), 500u);
  int64_t worst_gap = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (double v : poses[i].state) ASSERT_TRUE(std::isfinite(v)) << i;
    if (i > 0) worst_gap = std::max(worst_gap, poses[i].utime - poses[i - 1].utime);
  }
  EXPECT_LE(worst_gap, 2 * step) << "POSE kept the odometry's rate";
  ASSERT_FALSE(status.empty());
  ASSERT_EQ(status.back().event, "stopped") << daemon.output();
  for (const auto& kind : all)
    for (const std::string& counted : expectedCounts())
      EXPECT_NE(status.back().detail.find(kind.channel + counted), std::string::npos)
          << kind.channel << counted << "\n" << status.back().detail;
}
