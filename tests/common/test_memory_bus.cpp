// MemoryBus: the in-memory MessageBus the daemon's and the logger's unit tests run on.
#include <gtest/gtest.h>

#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/odometry_t.hpp"

using namespace lcmloc;
using bus::MemoryBus;

namespace {

lcmloc::odometry_t odo(int64_t seq) {
  lcmloc::odometry_t m{};
  m.utime = 1000 + seq;
  m.seq = seq;
  m.delta_s = 0.25 * static_cast<double>(seq);
  return m;
}

/// The channels (of ODOMETRY messages published on each) that a subscription to regex receives.
std::vector<std::string> received(const std::string& regex, const std::vector<std::string>& channels) {
  MemoryBus bus;
  std::vector<std::string> got;
  bus.subscribeRaw(regex, [&](const std::string& ch, const uint8_t*, std::size_t, int64_t) { got.push_back(ch); });
  for (const auto& ch : channels) bus.publish(ch, odo(0));
  bus.deliverAll();
  return got;
}

}  // namespace

TEST(MemoryBus, RecordsWhatIsPublishedAndDeliversItOnHandleOnly) {
  MemoryBus bus;
  std::vector<lcmloc::odometry_t> got;
  bus.subscribe<lcmloc::odometry_t>("ODOMETRY", [&](const std::string&, const lcmloc::odometry_t& m, int64_t) {
    got.push_back(m);
  });
  ASSERT_TRUE(bus.publish("ODOMETRY", odo(1)));
  ASSERT_TRUE(bus.publish("ODOMETRY", odo(2)));
  EXPECT_TRUE(got.empty()) << "a handler is never called from inside publish";
  EXPECT_EQ(bus.queued(), 2u);
  ASSERT_EQ(bus.published().size(), 2u);
  EXPECT_EQ(bus.published()[0].channel, "ODOMETRY");
  EXPECT_EQ(bus.published()[1].data, MemoryBus::encode(odo(2))) << "the bytes as encoded";

  EXPECT_EQ(bus.handle(), 1);  // the oldest first
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].seq, 1);
  EXPECT_EQ(bus.handle(), 1);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].seq, 2);
  EXPECT_EQ(got[1].delta_s, 0.5);
  EXPECT_EQ(bus.handle(100), 0) << "nothing queued";
  EXPECT_EQ(bus.decoded<lcmloc::odometry_t>("ODOMETRY").at(1).seq, 2);
  EXPECT_TRUE(bus.published("POSE").empty());
}

TEST(MemoryBus, ChannelsMatchAsLcmMatchesThem) {
  // A POSIX extended regex surrounded by ^ and $: the whole name, not a part of it.
  EXPECT_EQ(received("POSE", {"POSE", "POSE_UKF", "XPOSE"}), std::vector<std::string>({"POSE"}));
  EXPECT_EQ(received("POSE_.*", {"POSE", "POSE_UKF", "POSE_EKF"}), std::vector<std::string>({"POSE_UKF", "POSE_EKF"}));
  EXPECT_EQ(received(".*", {"A", "B"}), std::vector<std::string>({"A", "B"}));
  // ^A|B$ binds the anchors to the first and the last alternative only (why the logger groups
  // the channels it records); grouped, each alternative is a whole name.
  EXPECT_EQ(received("A|B", {"A", "AX", "XB", "XAX"}), std::vector<std::string>({"A", "AX", "XB"}));
  EXPECT_EQ(received("(A|B)", {"A", "AX", "XB", "B"}), std::vector<std::string>({"A", "B"}));
  MemoryBus bus;
  EXPECT_THROW(bus.subscribeRaw("(POSE", [](const std::string&, const uint8_t*, std::size_t, int64_t) {}),
               bus::TransportError);
}

TEST(MemoryBus, EveryMatchingSubscriptionGetsTheMessageInTheOrderSubscribed) {
  MemoryBus bus;
  std::vector<std::string> calls;
  bus.subscribeRaw("ODOMETRY", [&](const std::string&, const uint8_t*, std::size_t, int64_t) { calls.push_back("a"); });
  bus.subscribeRaw(".*", [&](const std::string&, const uint8_t*, std::size_t, int64_t) { calls.push_back("b"); });
  bus.subscribeRaw("GPS", [&](const std::string&, const uint8_t*, std::size_t, int64_t) { calls.push_back("c"); });
  EXPECT_EQ(bus.subscribers("ODOMETRY"), 2);
  bus.publish("ODOMETRY", odo(0));
  EXPECT_EQ(bus.deliverAll(), 1u);
  EXPECT_EQ(calls, std::vector<std::string>({"a", "b"}));
}

TEST(MemoryBus, InjectedBytesAreDeliveredButNotRecordedAsPublished) {
  MemoryBus bus;
  int good = 0;
  std::vector<std::string> errors;
  bus.subscribe<lcmloc::odometry_t>(
      "ODOMETRY", [&](const std::string&, const lcmloc::odometry_t&, int64_t) { ++good; },
      [&](const std::string& ch, const std::string& why) { errors.push_back(ch + ": " + why); });
  bus.setRecvUtime(777);
  bus.inject("ODOMETRY", std::vector<uint8_t>{1, 2, 3});  // not an odometry_t
  bus.inject("ODOMETRY", odo(5));
  int64_t recv = 0;
  bus.subscribeRaw("ODOMETRY", [&](const std::string&, const uint8_t*, std::size_t, int64_t r) { recv = r; });
  EXPECT_EQ(bus.deliverAll(), 2u);
  EXPECT_EQ(good, 1);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("ODOMETRY: cannot decode odometry_t"), std::string::npos) << errors[0];
  EXPECT_EQ(bus.decodeErrors("ODOMETRY"), 1);
  EXPECT_EQ(bus.decodeErrors(), 1);
  EXPECT_TRUE(bus.published().empty());
  EXPECT_EQ(recv, 777);
}

TEST(MemoryBus, WhatHandlersPublishIsDeliveredAfterwardsInOrder) {
  MemoryBus bus;
  std::vector<std::string> order;
  bus.subscribeRaw("PING", [&](const std::string& ch, const uint8_t*, std::size_t, int64_t) {
    order.push_back(ch);
    bus.publish("PONG", odo(0));
    order.push_back("published");  // the PONG handler has not run inside publish
  });
  bus.subscribeRaw("PONG", [&](const std::string& ch, const uint8_t*, std::size_t, int64_t) { order.push_back(ch); });
  bus.publish("PING", odo(0));
  bus.publish("PING", odo(1));
  EXPECT_EQ(bus.deliverAll(), 4u);
  EXPECT_EQ(order, std::vector<std::string>({"PING", "published", "PING", "published", "PONG", "PONG"}));
  EXPECT_TRUE(bus.drain());
  EXPECT_EQ(bus.queued(), 0u);

  // Handlers that keep each other busy forever: deliverAll says so instead of looping.
  bus.subscribeRaw("PONG", [&](const std::string&, const uint8_t*, std::size_t, int64_t) { bus.publish("PING", odo(0)); });
  bus.publish("PING", odo(0));
  EXPECT_THROW(bus.deliverAll(1000), std::runtime_error);
}
