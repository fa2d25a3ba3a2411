// Three hosts in network namespaces joined by a bridge (as root): the simulator and the drivers on
// one (under lcmloc-launcher), the fusion daemon on a second, the logger and the evaluation on a
// third, over udpm with ttl=1 and a multicast route to the bridge. The canonical POSE is byte for
// byte that of the same system on one host, the logger records every channel without a sequence
// gap, and every heartbeat names its host. Skips, saying why, without root or `ip netns`.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "netns.hpp"
#include "process_fixture.hpp"
#include "lcmloc/heartbeat_t.hpp"

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

int64_t seqOf(const std::vector<uint8_t>& d) {
  uint64_t v = 0;
  for (int i = 16; i < 24; ++i) v = (v << 8) | d[static_cast<std::size_t>(i)];
  return static_cast<int64_t>(v);
}

/// Waits until the child's output holds text (the process's own report that it is ready).
bool waitOutput(const Child& c, const std::string& text, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  while (c.output().find(text) == std::string::npos && Clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  return c.output().find(text) != std::string::npos;
}

class MultiHostTest : public ProcessFixture {
 protected:
  void SetUp() override {
    ProcessFixture::SetUp();
    if (const std::string why = netnsUnavailable(); !why.empty()) GTEST_SKIP() << why;
    url_ = url_.substr(0, url_.find('?')) + "?ttl=1&recv_buf_size=4194304";
  }

  /// The system with its parts on hosts[0] (simulator and drivers, under a launcher), hosts[1]
  /// (fusion) and hosts[2] (logger, writing log); the same namespace three times = one host.
  void runSystem(const std::array<const NetNs*, 3>& hosts, const std::string& log, const std::string& tag) {
    const std::string scenario = writeFile(tag + "_scenario.yaml", "scenario: {realtime_factor: 2}\n"
                                                                   "fusion: {reorder_window: 0.5}\n");
    const std::string drivers = writeFile(
        tag + "_drivers.yaml",
        "processes:\n"
        "  - {name: fault_injector, executable: " LCMLOC_FAULT_INJECTOR "}\n"
        "  - {name: magruler, executable: " LCMLOC_MAGRULER "}\n"
        "  - {name: odometry, executable: " LCMLOC_ODOMETRY "}\n"
        "  - {name: sim, executable: " LCMLOC_SIM ", until_exit: true}\n");
    const bool one = hosts[0] == hosts[1];
    const auto host = [&](int i) { return one ? std::string("solo") : "host" + std::to_string(i + 1); };
    Child logger(ipProgram(), hosts[2]->exec(LCMLOC_LOGGER, {"--config", scenario, "--lcm-url", url_, "-o", log}, host(2)),
                 path(tag + "_logger.out"));
    ASSERT_TRUE(waitOutput(logger, "recording '", 10s)) << logger.output();
    Child fusion(ipProgram(), hosts[1]->exec(LCMLOC_FUSION, {"--config", scenario, "--lcm-url", url_}, host(1)),
                 path(tag + "_fusion.out"));
    ASSERT_TRUE(waitOutput(fusion, "filter ukf_gated", 10s)) << fusion.output();
    Child launcher(ipProgram(),
                   hosts[0]->exec(LCMLOC_LAUNCHER, {"--system", drivers, "--config", scenario, "--lcm-url", url_}, host(0)),
                   path(tag + "_launcher.out"));
    if (!one) {
      // lcmloc-preflight on the third host while the system runs: every channel has a publisher,
      // and the other hosts' clocks (one kernel's here) are within 10 ms of its own.
      Child pre(ipProgram(),
                hosts[2]->exec(LCMLOC_PREFLIGHT, {"--lcm-url", url_, "--multi-host", "--expect",
                                                  "GROUND_TRUTH,ODOMETRY,POSE,HEARTBEAT", "--listen", "3"},
                               host(2)),
                path(tag + "_preflight.out"));
      EXPECT_EQ(pre.wait(30s), std::optional<int>(0)) << pre.output();
      for (const char* ok : {"ok    route: 239.255.76.67 goes out via v3", "ok    ttl: ttl=1", "ok    channel POSE",
                             "ok    clock host1", "ok    clock host2", "ok    clock host3"})
        EXPECT_NE(pre.output().find(ok), std::string::npos) << ok << "\n" << pre.output();
      std::printf("preflight on host3 during the run:\n%s", pre.output().c_str());
    }
    const auto rc = launcher.wait(90s);
    ASSERT_TRUE(rc.has_value()) << launcher.output();
    ASSERT_EQ(*rc, 0) << launcher.output();
    fusion.signal(SIGTERM);
    ASSERT_EQ(fusion.wait(20s), std::optional<int>(0)) << fusion.output();
    logger.signal(SIGTERM);
    ASSERT_EQ(logger.wait(20s), std::optional<int>(0)) << logger.output();
  }
};

TEST_F(MultiHostTest, ThreeHostsGiveTheOneHostPoseAndTheLoggerMissesNothing) {
  // One host: its own namespace, multicast on lo.
  NetNs solo("solo");
  ASSERT_TRUE(solo.ok());
  ASSERT_TRUE(solo.ip("route add 224.0.0.0/4 dev lo"));
  const std::string one_log = path("one_host.lcmlog");
  ASSERT_NO_FATAL_FAILURE(runSystem({&solo, &solo, &solo}, one_log, "one"));

  // Three hosts on a bridge (in a namespace of its own), multicast routed to their veth.
  NetNs sw("sw"), h1("h1"), h2("h2"), h3("h3");
  ASSERT_TRUE(sw.ok() && h1.ok() && h2.ok() && h3.ok());
  ASSERT_TRUE(sw.ip("link add br0 type bridge") && sw.ip("link set br0 up"));
  int k = 1;
  for (const NetNs* h : {&h1, &h2, &h3}) {
    const std::string v = "v" + std::to_string(k), p = "p" + std::to_string(k);
    ASSERT_TRUE(sw.ip("link add " + p + " type veth peer name " + v + " netns " + h->name()));
    ASSERT_TRUE(sw.ip("link set " + p + " master br0") && sw.ip("link set " + p + " up"));
    ASSERT_TRUE(h->ip("addr add 10.77.0." + std::to_string(k) + "/24 dev " + v) && h->ip("link set " + v + " up"));
    ASSERT_TRUE(h->ip("route add 224.0.0.0/4 dev " + v));
    ++k;
  }
  const std::string three_log = path("three_hosts.lcmlog");
  ASSERT_NO_FATAL_FAILURE(runSystem({&h1, &h2, &h3}, three_log, "three"));

  const auto one = readLog(one_log), three = readLog(three_log);
  std::vector<std::vector<uint8_t>> pose_one, pose_three;
  for (const auto& ev : one)
    if (ev.channel == "POSE") pose_one.push_back(ev.data);
  std::map<std::string, int64_t> count;
  std::map<std::string, int64_t> last_seq;
  std::set<std::string> hosts;
  int64_t gaps = 0;
  for (const auto& ev : three) {
    ++count[ev.channel];
    if (ev.channel == "POSE") pose_three.push_back(ev.data);
    // (LCM's self-test and whatever else is too short for a fingerprint, a utime and a seq carry
    // no seq of ours)
    if (ev.channel == "LCM_SELF_TEST" || ev.data.size() < 24) continue;
    std::string key = ev.channel;
    if (ev.channel == "HEARTBEAT") {
      const auto hb = decode<lcmloc::heartbeat_t>(ev);
      key += "[" + hb.host + "/" + std::to_string(hb.pid) + "]";
      hosts.insert(hb.process + "@" + hb.host);
    }
    const int64_t seq = seqOf(ev.data);
    if (last_seq.count(key) && seq != last_seq[key] + 1) ++gaps;
    last_seq[key] = seq;
  }
  std::printf("three hosts: %zu events, %zu POSE (one host: %zu), %lld sequence gaps\n", three.size(),
              pose_three.size(), pose_one.size(), static_cast<long long>(gaps));
  for (const char* ch : {"GROUND_TRUTH", "ODOMETRY", "MAGRULER", "MAGRULER_FAULT", "FAULT_EVENTS", "POSE", "GATE",
                         "FUSION_STATUS", "HEARTBEAT", "LOGGER_STATUS"})
    EXPECT_GT(count[ch], 0) << ch << " not recorded on the third host";
  EXPECT_EQ(gaps, 0);
  ASSERT_GT(pose_one.size(), 1000u);
  EXPECT_TRUE(pose_three == pose_one) << "the canonical POSE differs from the one-host run";
  for (const char* who : {"lcmloc-sim@host1", "lcmloc-odometry@host1", "lcmloc-magruler@host1",
                          "lcmloc-fault-injector@host1", "lcmloc-launcher@host1", "lcmloc-fusion@host2",
                          "lcmloc-logger@host3"})
    EXPECT_TRUE(hosts.count(who)) << who << " (heartbeats name their host)";

  // The evaluation on the third host, from its log.
  Child eval(ipProgram(), h3.exec(LCMLOC_EVALUATE, {three_log, "-o", path("eval")}, "host3"), path("eval.out"));
  EXPECT_EQ(eval.wait(60s), std::optional<int>(0)) << eval.output();
  EXPECT_TRUE(std::filesystem::exists(path("eval/report.json")));
}

}  // namespace
