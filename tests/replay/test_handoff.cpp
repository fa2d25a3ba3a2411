// The replay's hand-over of blocks between its reading and applying threads: order, reuse, the
// batched wake-ups, the end of the blocks and stop().
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <set>
#include <thread>
#include <vector>

#include "handoff.hpp"

using lcmloc::replay::Handoff;
using namespace std::chrono_literals;

namespace {

struct Numbered {
  int n = -1;
};

/// Produces `count` numbered blocks (the last one marked) on a thread while the caller consumes
/// them; each side pauses for its delay per block. Returns the numbers in the order received and
/// the distinct blocks seen.
struct Traffic {
  std::vector<int> received;
  std::set<const Numbered*> blocks;
  int64_t sleeps = 0;
};
Traffic run(Handoff<Numbered>& h, int count, std::chrono::microseconds produce, std::chrono::microseconds consume) {
  Traffic r;
  std::thread producer([&] {
    for (int i = 0; i < count; ++i) {
      Numbered* b = h.acquire();
      if (!b) return;
      std::this_thread::sleep_for(produce);
      b->n = i;
      h.publish(b, i == count - 1);
    }
  });
  for (int i = 0; i < count; ++i) {
    Numbered* b = h.take();
    r.received.push_back(b->n);
    r.blocks.insert(b);
    std::this_thread::sleep_for(consume);
    h.release(b);
  }
  h.stop();
  producer.join();
  r.sleeps = h.sleeps();
  return r;
}

std::vector<int> upTo(int count) {
  std::vector<int> v;
  for (int i = 0; i < count; ++i) v.push_back(i);
  return v;
}

}  // namespace

TEST(Handoff, BlocksArriveInOrderAndAreReusedNoMoreThanCapacityInFlight) {
  Handoff<Numbered> h(4, 2);
  const Traffic r = run(h, 200, 0us, 0us);
  EXPECT_EQ(r.received, upTo(200));
  EXPECT_LE(r.blocks.size(), 4u);
}

TEST(Handoff, AProducerAheadOfItsConsumerIsWokenOncePerBatchNotPerBlock) {
  // The consumer is the slow side: the producer fills every free block and waits. Woken at each
  // released block it would sleep about once per block (40); woken once 4 are free, at most once
  // per 4 (and the consumer once at the start, waiting for the first batch).
  Handoff<Numbered> h(8, 4);
  const Traffic r = run(h, 40, 0us, 1000us);
  EXPECT_EQ(r.received, upTo(40));
  EXPECT_GE(r.sleeps, 5);       // the producer did wait: what is counted happened
  EXPECT_LE(r.sleeps, 40 / 4 + 2);
}

TEST(Handoff, AConsumerAheadOfItsProducerWaitsForABatchAndTakesTheLastShortOne) {
  // 41 blocks: the last batch holds one block, handed over because it is the last.
  Handoff<Numbered> h(8, 4);
  const Traffic r = run(h, 41, 1000us, 0us);
  EXPECT_EQ(r.received, upTo(41));
  EXPECT_GE(r.sleeps, 5);
  EXPECT_LE(r.sleeps, 41 / 4 + 2);
}

TEST(Handoff, TheConsumersFirstBlockIsHandedOverAtOnceNotWithABatch) {
  // At the start the consumer has nothing to work on: it gets the first block as soon as it is
  // published (later it waits for a batch of 4). The producer publishes one block, then waits
  // until the consumer has it (up to 5 s) before it publishes the rest.
  Handoff<Numbered> h(8, 4);
  std::atomic<bool> got_first{false};
  bool waited_in_vain = true;
  std::thread producer([&] {
    Numbered* b = h.acquire();
    b->n = 0;
    h.publish(b);
    for (int i = 0; i < 500 && waited_in_vain; ++i) {
      if (got_first) waited_in_vain = false;
      else std::this_thread::sleep_for(10ms);
    }
    for (int i = 1; i < 8; ++i) {
      Numbered* c = h.acquire();
      c->n = i;
      h.publish(c, i == 7);
    }
  });
  Numbered* first = h.take();
  got_first = true;
  std::vector<int> received{first->n};
  h.release(first);
  while (Numbered* b = h.take()) {
    received.push_back(b->n);
    h.release(b);
  }
  producer.join();
  EXPECT_FALSE(waited_in_vain) << "the first block waited for a batch: take() returned only after the producer gave up";
  EXPECT_EQ(received, upTo(8));
}

TEST(Handoff, ABatchLargerThanHalfTheBlocksIsCutSoThatNeitherSideWaitsForTheOther) {
  // 3 blocks, batches of 5 asked: both sides asleep, each for blocks the other holds, would be a
  // deadlock; the batch is cut to 2. Both sides slow in turn: either may be the one waiting.
  Handoff<Numbered> h(3, 5);
  const Traffic a = run(h, 30, 300us, 0us);
  EXPECT_EQ(a.received, upTo(30));
  Handoff<Numbered> g(3, 5);
  const Traffic b = run(g, 30, 0us, 300us);
  EXPECT_EQ(b.received, upTo(30));
}

TEST(Handoff, AfterTheLastBlockTakeSaysSoInsteadOfWaitingForever) {
  Handoff<Numbered> h(4, 2);
  Numbered* a = h.acquire();
  a->n = 7;
  h.publish(a, true);
  Numbered* got = h.take();
  ASSERT_EQ(got, a);
  EXPECT_EQ(got->n, 7);
  h.release(got);
  EXPECT_EQ(h.take(), nullptr);
}

TEST(Handoff, StopWakesAProducerWaitingForAFreeBlock) {
  Handoff<Numbered> h(2, 1);
  Numbered* a = h.acquire();
  Numbered* b = h.acquire();
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  Numbered* third = a;  // (not nullptr: the producer's result is checked after stop)
  std::thread producer([&] { third = h.acquire(); });
  std::this_thread::sleep_for(20ms);
  h.stop();
  producer.join();
  EXPECT_EQ(third, nullptr);
  EXPECT_EQ(h.acquire(), nullptr);  // and after stop, at once
}
