// bus::Bus receiving on its own socket (udpm_receiver.hpp) over real udpm on loopback, next to
// LCM's own publisher and receiver: the same messages, whole and in order, as LCM delivers them.
#include <cstdlib>
#include <chrono>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "lcmloc/bus/transport.hpp"
#include "process_fixture.hpp"

namespace {

using namespace std::chrono_literals;
using lcmloc::bus::Bus;

struct Got {
  std::string channel;
  std::vector<uint8_t> data;
  int64_t recv_utime;
  int route;
};

class UdpmProcess : public ProcessFixture {
 protected:
  /// Subscribes `bus` the way the tests below look at it: route 0 "POSE.*", route 1 "POSE",
  /// route 2 "BIG".
  static void subscribeAll(Bus& bus, std::vector<Got>& got) {
    int route = 0;
    for (const char* ch : {"POSE.*", "POSE", "BIG"}) {
      bus.subscribeRaw(ch, [&got, route](const std::string& c, const uint8_t* d, std::size_t n, int64_t t) {
        got.push_back(Got{c, std::vector<uint8_t>(d, d + n), t, route});
      });
      ++route;
    }
  }
  static void waitFor(Bus& bus, const std::vector<Got>& got, std::size_t n) {
    const auto until = std::chrono::steady_clock::now() + 10s;
    while (got.size() < n && std::chrono::steady_clock::now() < until) bus.handle(50);
  }
  /// What `bus` receives of LCM's publishes: small ones, one fragmented by LCM, others no one
  /// subscribes to in between.
  void receivesWhatLcmSends(Bus& bus) {
    std::vector<Got> got;
    subscribeAll(bus, got);
    lcm::LCM sender(url_);
    ASSERT_TRUE(sender.good());
    std::vector<uint8_t> big(300000);
    for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<uint8_t>(i * 31 + i / 977);
    const std::vector<uint8_t> small{1, 2, 3, 4, 5};
    const int64_t before = lcmloc::bus::wallMicros();
    sender.publish("XPOSE", small.data(), 5);  // matches no route (anchored at both ends)
    sender.publish("POSE", small.data(), 5);
    sender.publish("BIG", big.data(), static_cast<unsigned>(big.size()));
    sender.publish("POSE_CONTROL", small.data(), 3);
    sender.publish("UNSUBSCRIBED", big.data(), static_cast<unsigned>(big.size()));
    waitFor(bus, got, 4);
    bus.handle(100);  // (nothing more may come)
    ASSERT_EQ(got.size(), 4u);
    EXPECT_EQ(got[0].channel, "POSE");  // both of its routes, in the order subscribed
    EXPECT_EQ(got[0].route, 0);
    EXPECT_EQ(got[1].channel, "POSE");
    EXPECT_EQ(got[1].route, 1);
    EXPECT_EQ(got[0].data, small);
    EXPECT_EQ(got[2].channel, "BIG");
    EXPECT_TRUE(got[2].data == big) << got[2].data.size() << " bytes";
    EXPECT_EQ(got[3].channel, "POSE_CONTROL");
    EXPECT_EQ(got[3].route, 0);
    EXPECT_EQ(got[3].data, std::vector<uint8_t>(small.begin(), small.begin() + 3));
    for (const Got& g : got) {
      EXPECT_GE(g.recv_utime, before - 1000);  // the kernel's receive time, on the wall clock
      EXPECT_LE(g.recv_utime, lcmloc::bus::wallMicros());
    }
    // A burst: 5000 messages back to back, each one there, in order.
    got.clear();
    for (uint32_t k = 0; k < 5000; ++k) {
      const uint8_t b[4] = {uint8_t(k >> 24), uint8_t(k >> 16), uint8_t(k >> 8), uint8_t(k)};
      sender.publish("POSE_BURST", b, 4);
    }
    waitFor(bus, got, 5000);
    ASSERT_EQ(got.size(), 5000u);
    for (uint32_t k = 0; k < 5000; ++k)
      ASSERT_EQ(got[k].data, (std::vector<uint8_t>{uint8_t(k >> 24), uint8_t(k >> 16), uint8_t(k >> 8), uint8_t(k)}));
  }
};

TEST_F(UdpmProcess, TheOwnReceiveGetsWhatLcmSendsWholeAndInOrder) {
  Bus bus(url_);
  ASSERT_TRUE(bus.ownReceive());
  receivesWhatLcmSends(bus);
}

TEST_F(UdpmProcess, LcmsOwnReceiveGetsTheSameWhenAskedFor) {
  ::setenv("LCMLOC_LCM_RECEIVE", "lcm", 1);
  Bus bus(url_);
  ::unsetenv("LCMLOC_LCM_RECEIVE");
  ASSERT_FALSE(bus.ownReceive());
  receivesWhatLcmSends(bus);
}

TEST_F(UdpmProcess, LcmReceivesWhatTheBusPublishesAndABadRegexIsAnError) {
  Bus bus(url_);
  ASSERT_TRUE(bus.ownReceive());
  lcm::LCM receiver(url_);
  struct Sink {
    std::vector<std::vector<uint8_t>> got;
    void on(const lcm::ReceiveBuffer* rb, const std::string&) {
      const auto* d = static_cast<const uint8_t*>(rb->data);
      got.emplace_back(d, d + rb->data_size);
    }
  } sink;
  receiver.subscribe("FROM_BUS", &Sink::on, &sink);
  std::vector<uint8_t> big(100000, 7);
  ASSERT_TRUE(bus.publishRaw("FROM_BUS", big.data(), big.size()));
  const auto until = std::chrono::steady_clock::now() + 5s;
  while (sink.got.empty() && std::chrono::steady_clock::now() < until) receiver.handleTimeout(50);
  ASSERT_EQ(sink.got.size(), 1u);
  EXPECT_EQ(sink.got[0], big);
  EXPECT_THROW(bus.subscribeRaw("POSE[", [](const std::string&, const uint8_t*, std::size_t, int64_t) {}),
               lcmloc::bus::TransportError);
  // With nothing subscribed, handle() waits its time and says nothing came.
  Bus idle(url_);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(idle.handle(100), 0);
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 90ms);
}

}  // namespace
