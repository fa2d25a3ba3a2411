// bus::UdpmAssembler and parseUdpmUrl: LCM 1.3.1's udpm datagrams turned into messages, and the
// URL read as LCM reads it (udpm_receiver.hpp). Over real sockets: tests/process/test_udpm_process.cpp.
#include <gtest/gtest.h>

#include <arpa/inet.h>

#include <cstdint>
#include <string>
#include <vector>

#include "lcmloc/bus/udpm_receiver.hpp"

namespace {

using lcmloc::bus::parseUdpmUrl;
using lcmloc::bus::UdpmAssembler;
using lcmloc::bus::UdpmMessage;
using Result = UdpmAssembler::Result;
using Bytes = std::vector<uint8_t>;

void put32(Bytes& b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<uint8_t>(v >> s));
}
void put16(Bytes& b, uint16_t v) {
  b.push_back(static_cast<uint8_t>(v >> 8));
  b.push_back(static_cast<uint8_t>(v));
}

Bytes shortDatagram(uint32_t seqno, const std::string& channel, const Bytes& payload) {
  Bytes b;
  put32(b, 0x4c433032);
  put32(b, seqno);
  b.insert(b.end(), channel.begin(), channel.end());
  b.push_back(0);
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}

/// The fragments LCM 1.3.1 sends for one message, fragment bytes each (fragment 0: the channel too).
std::vector<Bytes> fragments(uint32_t seqno, const std::string& channel, const Bytes& payload, std::size_t fragment) {
  std::vector<Bytes> pieces;
  const std::size_t first = fragment - channel.size() - 1;
  pieces.emplace_back(payload.begin(), payload.begin() + static_cast<long>(std::min(first, payload.size())));
  for (std::size_t at = first; at < payload.size(); at += fragment)
    pieces.emplace_back(payload.begin() + static_cast<long>(at),
                        payload.begin() + static_cast<long>(std::min(at + fragment, payload.size())));
  std::vector<Bytes> out;
  uint32_t offset = 0;
  for (std::size_t no = 0; no < pieces.size(); ++no) {
    Bytes b;
    put32(b, 0x4c433033);
    put32(b, seqno);
    put32(b, static_cast<uint32_t>(payload.size()));
    put32(b, offset);
    put16(b, static_cast<uint16_t>(no));
    put16(b, static_cast<uint16_t>(pieces.size()));
    if (no == 0) {
      b.insert(b.end(), channel.begin(), channel.end());
      b.push_back(0);
    }
    b.insert(b.end(), pieces[no].begin(), pieces[no].end());
    offset += static_cast<uint32_t>(pieces[no].size());
    out.push_back(std::move(b));
  }
  return out;
}

Bytes payloadOf(std::size_t n) {
  Bytes p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<uint8_t>(i * 7 + i / 256);
  return p;
}

struct Feed {
  UdpmAssembler a;
  std::vector<std::pair<std::string, Bytes>> got;
  std::function<bool(std::string_view)> wanted = [](std::string_view ch) { return ch != "IGNORED"; };
  Result add(const Bytes& d, uint64_t sender = 1) {
    UdpmMessage m;
    const Result r = a.add(d.data(), d.size(), sender, 42, wanted, &m);
    if (r == Result::Message) {
      EXPECT_EQ(m.recv_utime, 42);
      got.emplace_back(std::string(m.channel), Bytes(m.data, m.data + m.size));
    }
    return r;
  }
};

TEST(Udpm, TheUrlIsReadAsLcmReadsIt) {
  const auto d = parseUdpmUrl("udpm://");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->group, 0xEFFF4C43u);  // 239.255.76.67
  EXPECT_EQ(d->port, 7667);
  EXPECT_EQ(d->recv_buf_size, 0);
  const auto u = parseUdpmUrl("udpm://239.255.76.68:20001?ttl=1&recv_buf_size=4194304");
  ASSERT_TRUE(u);
  EXPECT_EQ(u->group, 0xEFFF4C44u);
  EXPECT_EQ(u->port, 20001);
  EXPECT_EQ(u->recv_buf_size, 4194304);
  EXPECT_EQ(parseUdpmUrl("udpm://239.255.76.67")->port, 0);  // LCM too leaves the port 0 then
  // Not for this receiver: another provider, a bad address or port, an option LCM does not read.
  EXPECT_FALSE(parseUdpmUrl("memq://"));
  EXPECT_FALSE(parseUdpmUrl("file:///tmp/x.lcmlog"));
  EXPECT_FALSE(parseUdpmUrl("udpm://239.255.300.1:7667"));
  EXPECT_FALSE(parseUdpmUrl("udpm://239.255.76.67:70000"));
  EXPECT_FALSE(parseUdpmUrl("udpm://239.255.76.67:7667?transmit_only=true"));
}

TEST(Udpm, AShortMessageIsItsDatagramAfterTheChannel) {
  Feed f;
  const Bytes p = payloadOf(57);
  EXPECT_EQ(f.add(shortDatagram(3, "ODOMETRY", p)), Result::Message);
  EXPECT_EQ(f.add(shortDatagram(4, "ODOMETRY", {})), Result::Message);  // an empty payload is a message
  ASSERT_EQ(f.got.size(), 2u);
  EXPECT_EQ(f.got[0].first, "ODOMETRY");
  EXPECT_EQ(f.got[0].second, p);
  EXPECT_TRUE(f.got[1].second.empty());
}

TEST(Udpm, ADatagramThatIsNotLcmIsBad) {
  Feed f;
  Bytes wrong = shortDatagram(1, "ODOMETRY", payloadOf(8));
  wrong[3] = 0x31;  // "LC01"
  EXPECT_EQ(f.add(wrong), Result::Bad);
  EXPECT_EQ(f.add(Bytes{0x4c, 0x43, 0x30}), Result::Bad);  // shorter than a header
  Bytes unterminated = shortDatagram(1, "ODOMETRY", {});
  unterminated.pop_back();  // the channel's NUL
  EXPECT_EQ(f.add(unterminated), Result::Bad);
  EXPECT_EQ(f.add(shortDatagram(1, "", payloadOf(4))), Result::Bad);
  EXPECT_EQ(f.add(shortDatagram(1, std::string(64, 'C'), payloadOf(4))), Result::Bad);  // LCM's limit is 63
  EXPECT_EQ(f.add(shortDatagram(1, std::string(63, 'C'), payloadOf(4))), Result::Message);
  EXPECT_EQ(f.got.size(), 1u);
}

TEST(Udpm, FragmentsMakeTheMessageInAnyOrderAndOnce) {
  const Bytes p = payloadOf(5000);
  const auto frags = fragments(9, "FUSION_STATUS", p, 1400);
  ASSERT_EQ(frags.size(), 4u);
  Feed f;
  EXPECT_EQ(f.add(frags[0]), Result::Partial);
  EXPECT_EQ(f.add(frags[3]), Result::Partial);
  EXPECT_EQ(f.add(frags[3]), Result::Partial);  // a duplicate counts once
  EXPECT_EQ(f.add(frags[1]), Result::Partial);
  EXPECT_EQ(f.a.pendingSenders(), 1u);
  EXPECT_EQ(f.add(frags[2]), Result::Message);
  ASSERT_EQ(f.got.size(), 1u);
  EXPECT_EQ(f.got[0].first, "FUSION_STATUS");
  EXPECT_EQ(f.got[0].second, p);
  EXPECT_EQ(f.a.pendingSenders(), 0u);
  EXPECT_EQ(f.a.pendingBytes(), 0u);
}

TEST(Udpm, TwoSendersFragmentsInterleavedAreKeptApart) {
  const Bytes p = payloadOf(3000), q = payloadOf(2500);
  const auto a = fragments(1, "POSE", p, 1000), b = fragments(1, "POSE", q, 1000);
  Feed f;
  for (std::size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    if (i < a.size()) f.add(a[i], 10);
    if (i < b.size()) f.add(b[i], 11);
  }
  ASSERT_EQ(f.got.size(), 2u);
  EXPECT_EQ(f.got[0].second, q);  // (the shorter one is complete first)
  EXPECT_EQ(f.got[1].second, p);
}

TEST(Udpm, AMessageMissingAFragmentIsLostAndTheNextOneComesThrough) {
  const Bytes p = payloadOf(4000), q = payloadOf(3500);
  const auto lost = fragments(5, "POSE", p, 1000), next = fragments(6, "POSE", q, 1000);
  Feed f;
  for (std::size_t i = 0; i + 1 < lost.size(); ++i) f.add(lost[i]);  // its last fragment never comes
  for (const auto& d : next) f.add(d);
  ASSERT_EQ(f.got.size(), 1u);
  EXPECT_EQ(f.got[0].second, q);
  // Without its first fragment (the one with the channel) nothing is kept.
  Feed g;
  for (std::size_t i = 1; i < next.size(); ++i) EXPECT_EQ(g.add(next[i]), Result::Partial);
  EXPECT_TRUE(g.got.empty());
  EXPECT_EQ(g.a.pendingBytes(), 0u);
}

TEST(Udpm, AFragmentOutsideItsMessageIsBadAndDropsTheMessage) {
  const Bytes p = payloadOf(3000);
  auto frags = fragments(2, "POSE", p, 1000);
  frags[1][15] = 0xFF;  // its offset (low byte) beyond the message's end
  frags[1][14] = 0xFF;
  Feed f;
  EXPECT_EQ(f.add(frags[0]), Result::Partial);
  EXPECT_EQ(f.add(frags[1]), Result::Bad);
  EXPECT_EQ(f.a.pendingSenders(), 0u);
  for (std::size_t i = 2; i < frags.size(); ++i) f.add(frags[i]);
  EXPECT_TRUE(f.got.empty());
}

TEST(Udpm, AMessageNoOneSubscribesToIsNotReassembled) {
  Feed f;
  const auto frags = fragments(1, "IGNORED", payloadOf(3000), 1000);
  EXPECT_EQ(f.add(frags[0]), Result::Ignored);
  for (std::size_t i = 1; i < frags.size(); ++i) EXPECT_EQ(f.add(frags[i]), Result::Partial);
  EXPECT_EQ(f.add(shortDatagram(1, "IGNORED", payloadOf(10))), Result::Ignored);
  EXPECT_TRUE(f.got.empty());
  EXPECT_EQ(f.a.pendingBytes(), 0u);
}

TEST(Udpm, PartialMessagesStayWithinTheirBoundTheOldestGoing) {
  Feed f;
  const std::size_t senders = UdpmAssembler::kMaxPendingSenders + 20;
  for (std::size_t s = 0; s < senders; ++s) f.add(fragments(1, "POSE", payloadOf(3000), 1000)[0], s);
  EXPECT_EQ(f.a.pendingSenders(), UdpmAssembler::kMaxPendingSenders);
  // The newest senders' messages are still there: their rest completes them.
  for (const auto& d : fragments(1, "POSE", payloadOf(3000), 1000)) f.add(d, senders - 1);
  EXPECT_EQ(f.got.size(), 1u);
  // A message that claims more than the bound is refused, and claims of half the bound each push
  // out the one before.
  Feed g;
  Bytes huge = fragments(1, "POSE", payloadOf(3000), 1000)[0];
  huge[8] = 0x7F;  // its size: about 2 GB
  EXPECT_EQ(g.add(huge), Result::Bad);
  for (uint64_t s = 0; s < 5; ++s) {
    Bytes half = fragments(1, "POSE", payloadOf(3000), 1000)[0];
    const uint32_t size = static_cast<uint32_t>(UdpmAssembler::kMaxPendingBytes / 2);
    half[8] = static_cast<uint8_t>(size >> 24);
    half[9] = static_cast<uint8_t>(size >> 16);
    half[10] = static_cast<uint8_t>(size >> 8);
    half[11] = static_cast<uint8_t>(size);
    g.add(half, s);
    EXPECT_LE(g.a.pendingBytes(), UdpmAssembler::kMaxPendingBytes);
  }
  EXPECT_EQ(g.a.pendingSenders(), 2u);
}

}  // namespace
