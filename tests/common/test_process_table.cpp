// app::ProcessTable: launcher children by name, message rates from heartbeat counters, an earlier
// run of a child not shown as a process of its own, clock offsets per host; the heartbeat's own
// CPU and memory figures.
#include <gtest/gtest.h>

#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/process_table.hpp"
#include "lcmloc/bus/memory_bus.hpp"

using namespace lcmloc;
using app::ProcState;

namespace {

lcmloc::heartbeat_t beat(const std::string& process, const std::string& host, int32_t pid, int64_t seq,
                         int64_t utime, app::Heartbeat::Counters counters = {}) {
  lcmloc::heartbeat_t m{};
  m.process = process;
  m.host = host;
  m.pid = pid;
  m.seq = seq;
  m.utime = utime;
  m.state = "running";
  m.cpu_percent = 12.5f;
  m.rss_bytes = 3 * 1048576;
  for (auto& [n, v] : counters) {
    m.counter_names.push_back(n);
    m.counters.push_back(v);
  }
  m.num_counters = static_cast<int32_t>(m.counters.size());
  return m;
}

app::Heartbeat::Counters launcherCounters(int64_t odo_pid, ProcState state, int64_t restarts) {
  app::Heartbeat::Counters c{{"children", 1}};
  for (auto& kv : app::childCounters("odometry", odo_pid, state, restarts)) c.push_back(kv);
  return c;
}

TEST(ProcessTable, NamesLauncherChildrenAndComputesRates) {
  app::ProcessTable t;
  const auto t0 = app::ProcessTable::Clock::time_point{} + std::chrono::seconds(100);
  t.observe(beat("lcmloc-launcher", "a", 10, 0, 1000000, launcherCounters(11, ProcState::Running, 0)), 1000000, t0);
  t.observe(beat("lcmloc-odometry", "a", 11, 0, 1000000, {{"received", 100}, {"published", 50}}), 1000000, t0);
  t.observe(beat("lcmloc-odometry", "a", 11, 1, 3000000, {{"received", 300}, {"published", 250}}), 3000000, t0);
  t.observe(beat("lcmloc-fusion", "b", 11, 0, 2000000, {{"in", 7}}), 2000000, t0);  // same pid, other host
  const auto rows = t.rows(t0 + std::chrono::milliseconds(500));
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].name, "launcher");
  EXPECT_EQ(rows[1].name, "odometry");
  EXPECT_EQ(rows[1].state, "running");
  EXPECT_EQ(rows[1].restarts, 0);
  EXPECT_DOUBLE_EQ(rows[1].rate_in, 100.0);   // 200 in 2 s
  EXPECT_DOUBLE_EQ(rows[1].rate_out, 100.0);
  EXPECT_DOUBLE_EQ(rows[1].age, 0.5);
  EXPECT_FLOAT_EQ(static_cast<float>(rows[1].cpu_percent), 12.5f);
  EXPECT_EQ(rows[2].name, "lcmloc-fusion");
  EXPECT_EQ(rows[2].host, "b");
  EXPECT_EQ(rows[2].restarts, -1);  // not under a launcher seen
  EXPECT_LT(rows[2].rate_in, 0);    // one heartbeat: no rate yet
  const std::string text = app::formatProcessTable(rows);
  EXPECT_NE(text.find("odometry         a                    11 running           0   12.5       3.0      100      100    0.5"),
            std::string::npos)
      << text;
}

TEST(ProcessTable, AChildStartedAgainHidesItsEarlierRun) {
  app::ProcessTable t;
  t.observe(beat("lcmloc-launcher", "a", 10, 0, 0, launcherCounters(11, ProcState::Running, 0)), 0);
  t.observe(beat("lcmloc-odometry", "a", 11, 0, 0), 0);
  t.observe(beat("lcmloc-launcher", "a", 10, 1, 0, launcherCounters(12, ProcState::Starting, 1)), 0);
  t.observe(beat("lcmloc-odometry", "a", 12, 0, 0), 0);
  const auto rows = t.rows();
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1].pid, 12);
  EXPECT_EQ(rows[1].state, "starting");
  EXPECT_EQ(rows[1].restarts, 1);
}

TEST(ProcessTable, ClockOffsetIsTheMedianPerHost) {
  app::ProcessTable t;
  // Host b's clock 20 ms behind: received 20 ms (+ latency) after its stamp; one outlier.
  const int64_t lat[] = {20100, 20300, 20200, 90000, 20150};
  for (int i = 0; i < 5; ++i) t.observe(beat("p", "b", 5, i, 1000000 * i), 1000000 * i + lat[i]);
  t.observe(beat("q", "a", 6, 0, 5000000), 5000050);
  const auto c = t.clocks();
  ASSERT_EQ(c.size(), 2u);
  EXPECT_NEAR(c.at("b").offset, 0.0202, 1e-9);
  EXPECT_NEAR(c.at("b").spread, 0.0699, 1e-9);
  EXPECT_EQ(c.at("b").samples, 5);
  EXPECT_NEAR(c.at("a").offset, 0.00005, 1e-9);
}

TEST(Heartbeat, CarriesHostCpuAndMemory) {
  ::setenv("LCMLOC_HOST", "test-host-7", 1);
  bus::MemoryBus bus;
  app::Heartbeat hb(bus, "HEARTBEAT", "me");
  hb.publish("running");
  volatile double x = 0;  // some CPU time between the two heartbeats
  for (int i = 0; i < 20000000; ++i) x = x + i * 1e-9;
  hb.publish("running");
  ::unsetenv("LCMLOC_HOST");
  const auto got = bus.decoded<lcmloc::heartbeat_t>("HEARTBEAT");
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].host, "test-host-7");
  EXPECT_LT(got[0].cpu_percent, 0.0f);  // no previous heartbeat: not known
  EXPECT_GT(got[1].cpu_percent, 0.0f);
  EXPECT_GT(got[1].rss_bytes, 1 << 20);  // a process with gtest loaded holds more than 1 MB
  EXPECT_NE(app::hostName(), "test-host-7");  // without LCMLOC_HOST: the host name
  EXPECT_FALSE(app::hostName().empty());
}

}  // namespace
