// lcmloc-preflight in network namespaces (as root) set up to have each fault: no multicast route,
// a net.core.rmem_max below the URL's recv_buf_size, a channel without a publisher; and a healthy
// one that passes. Without root or `ip netns` the namespace tests skip, saying why.
//
// net.core.rmem_max is not per network namespace on the kernels this was written on (6.x: a
// namespace sees the host's value, read-only), so the too-small value is given through
// --rmem-max-file, the file preflight reads it from.
#include <gtest/gtest.h>

#include "netns.hpp"
#include "process_fixture.hpp"

using namespace std::chrono_literals;

namespace {

class PreflightTest : public ProcessFixture {
 protected:
  void SetUp() override {
    ProcessFixture::SetUp();
    if (const std::string why = netnsUnavailable(); !why.empty()) GTEST_SKIP() << why;
  }
  /// lcmloc-preflight in ns with args; its exit code and output.
  std::pair<int, std::string> preflight(const NetNs& ns, std::vector<std::string> args, const std::string& out) {
    args.insert(args.begin(), {"--lcm-url", url_});
    Child c(ipProgram(), ns.exec(LCMLOC_PREFLIGHT, args), path(out));
    const auto rc = c.wait(30s);
    return {rc.value_or(-1), c.output()};
  }
};

TEST_F(PreflightTest, FindsAMissingMulticastRoute) {
  NetNs ns("noroute");
  ASSERT_TRUE(ns.ok());
  const auto [rc, out] = preflight(ns, {"--listen", "0"}, "preflight.out");
  EXPECT_EQ(rc, 4) << out;
  EXPECT_NE(out.find("FAIL  route: no route to the multicast group 239.255.76.67"), std::string::npos) << out;
  EXPECT_NE(out.find("-> as root: ip route add 224.0.0.0/4 dev IFACE"), std::string::npos) << out;
  EXPECT_NE(out.find("FAIL  self-test: not tried: no route"), std::string::npos) << out;
}

TEST_F(PreflightTest, FindsATooSmallReceiveBufferLimit) {
  NetNs ns("rmem");
  ASSERT_TRUE(ns.ok());
  ASSERT_TRUE(ns.ip("route add 224.0.0.0/4 dev lo"));
  const std::string rmem = writeFile("rmem_max", "212992\n");
  const auto [rc, out] = preflight(ns, {"--listen", "0", "--rmem-max-file", rmem}, "preflight.out");
  EXPECT_EQ(rc, 4) << out;
  EXPECT_NE(out.find("FAIL  rmem_max: net.core.rmem_max = 212992"), std::string::npos) << out;
  EXPECT_NE(out.find("recv_buf_size=4194304 the URL asks for"), std::string::npos) << out;
  EXPECT_NE(out.find("-> as root: sysctl -w net.core.rmem_max=4194304"), std::string::npos) << out;
  EXPECT_NE(out.find("ok    route: 239.255.76.67 goes out via lo"), std::string::npos) << out;
  EXPECT_NE(out.find("ok    self-test"), std::string::npos) << out;
}

// The same healthy namespace with the simulator and the odometry driver running: the magnetic
// ruler's channel has no publisher (fails), and without it every check passes, the clock too.
TEST_F(PreflightTest, FindsASilentChannelAndPassesAHealthyNamespace) {
  NetNs ns("healthy");
  ASSERT_TRUE(ns.ok());
  ASSERT_TRUE(ns.ip("route add 224.0.0.0/4 dev lo"));
  const std::string rmem = writeFile("rmem_max", "8388608\n");
  const std::string scenario = writeFile("scenario.yaml", "scenario: {realtime_factor: 1}\n");
  Child sim(ipProgram(), ns.exec(LCMLOC_SIM, {"--config", scenario, "--lcm-url", url_}), path("sim.out"));
  Child odo(ipProgram(), ns.exec(LCMLOC_ODOMETRY, {"--config", scenario, "--lcm-url", url_}), path("odo.out"));
  const auto [rc_silent, out_silent] =
      preflight(ns, {"--expect", "GROUND_TRUTH,ODOMETRY,MAGRULER", "--listen", "2.5", "--rmem-max-file", rmem},
                "silent.out");
  EXPECT_EQ(rc_silent, 4) << out_silent;
  EXPECT_NE(out_silent.find("FAIL  channel MAGRULER: no publisher within 2.5 s"), std::string::npos) << out_silent;
  EXPECT_NE(out_silent.find("ok    channel ODOMETRY"), std::string::npos) << out_silent;

  const auto [rc, out] = preflight(
      ns, {"--expect", "GROUND_TRUTH,ODOMETRY,HEARTBEAT", "--listen", "2.5", "--rmem-max-file", rmem}, "healthy.out");
  EXPECT_EQ(rc, 0) << out;
  for (const char* check : {"route", "ttl", "rmem_max", "self-test", "channel GROUND_TRUTH", "channel ODOMETRY",
                            "channel HEARTBEAT", "clock "})
    EXPECT_NE(out.find(std::string("ok    ") + check), std::string::npos) << check << "\n" << out;
  EXPECT_EQ(out.find("FAIL"), std::string::npos) << out;
}

}  // namespace
