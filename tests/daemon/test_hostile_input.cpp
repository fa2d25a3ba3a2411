// Every kind of bad message on every input channel of a running daemon (over the MemoryBus):
// undecodable bytes, a right fingerprint with a cut body, NaN, a negative sigma, a time that is
// huge, negative or far back, a flood of copies. After each, the pose is finite, POSE keeps the
// odometry's rate, and the status counts the drop under its channel and reason.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "daemon/daemon.hpp"
#include "hostile_messages.hpp"
#include "lcmloc/fusion_status_t.hpp"

using namespace lcmloc;

namespace {
constexpr int64_t kT0 = 1000000;
constexpr int64_t kStep = 10000;  // 100 Hz odometry
using namespace lcmloc::hostile;
}  // namespace

TEST(HostileInput, EveryKindOfBadMessageOnEveryInputChannelIsCountedAndDroppedAndThePoseGoesOn) {
  const app::SystemConfig cfg = app::loadSystemConfig(LCMLOC_PAPER_YAML);
  bus::MemoryBus bus;
  fusion::FusionDaemon daemon(cfg, bus);
  const auto all = kinds(cfg.channels);
  std::map<std::string, int64_t> seq;
  int64_t k = 0;
  auto odo = [&](int64_t n) {
    for (int64_t i = 0; i < n; ++i, ++k) {
      bus.inject(cfg.channels.odometry, odometry(k, kT0 + k * kStep));
      bus.deliverAll();
    }
  };
  odo(100);
  for (const auto& bad : badKinds()) {
    for (const auto& kind : all) {
      // From the channel's own publisher: on ODOMETRY the next message of the stream is the bad
      // one (its seq and time), elsewhere a message between two odometry messages.
      const bool odometry_channel = kind.channel == cfg.channels.odometry;
      const int64_t t = odometry_channel ? kT0 + k * kStep : kT0 + k * kStep + 5000;
      const int64_t s = odometry_channel ? k++ : seq[kind.channel]++;
      const std::vector<uint8_t> bytes = badMessage(kind, bad, s, t);
      const int copies = bad == "flood" ? 100 : 1;
      for (int c = 0; c < copies; ++c) bus.inject(kind.channel, bytes);  // (flood: copies of one message)
      bus.deliverAll();
      odo(10);
    }
  }
  odo(300);
  daemon.shutdown();
  const auto poses = bus.decoded<lcmloc::pose_t>(cfg.channels.pose);
  ASSERT_GT(poses.size(), 500u);
  int64_t worst_gap = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (double v : poses[i].state) ASSERT_TRUE(std::isfinite(v)) << i;
    if (i > 0) worst_gap = std::max(worst_gap, poses[i].utime - poses[i - 1].utime);
  }
  EXPECT_LE(worst_gap, 2 * kStep) << "POSE kept the odometry's rate";
  const auto st = bus.decoded<lcmloc::fusion_status_t>(cfg.channels.status);
  ASSERT_FALSE(st.empty());
  ASSERT_EQ(st.back().event, "stopped");
  // Per channel: undecodable and cut undecodable; NaN, a negative sigma (or its kind's bad
  // value) and a negative time invalid; a time 2^61 too new; 99 of the 100 copies and the time
  // 1.5 s back too old.
  for (const auto& kind : all)
    for (const std::string& counted : expectedCounts())
      EXPECT_NE(st.back().detail.find(kind.channel + counted), std::string::npos)
          << kind.channel << counted << "\n" << st.back().detail;
  // The status events stayed few: at most 5 per channel and reason in a status period.
  int64_t rejected_events = 0;
  for (const auto& s : st) rejected_events += s.event == "rejected_input";
  EXPECT_LE(rejected_events, static_cast<int64_t>(all.size() * 4 * fusion::RejectBook::kEventsPerPeriod));
  // ODOMETRY's undecodable and cut messages had their seq in the stream: they count as lost.
  EXPECT_EQ(daemon.gaps(), 2);
}
