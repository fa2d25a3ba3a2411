#pragma once
// Blocks handed from one thread (the producer) to another (the consumer) in order, at most
// `capacity` in flight; the consumer gives each block back for reuse, so nothing is allocated
// once the blocks have grown. One lock per block: a block carries many items.
//
// A side that runs out of blocks sleeps until `batch` of them are ready for it (or the other
// side has finished), not until the first one is (except for the consumer's first block): then it works through several blocks before
// it waits again. On a virtual machine a wake-up is an interrupt to the other CPU, tens of
// microseconds of the waking side's time; with batch = capacity / 2 the faster side is woken
// once per batch blocks, not once per block.
#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <vector>

namespace lcmloc::replay {

template <typename Block>
class Handoff {
 public:
  /// capacity >= 1 blocks in flight; a sleeping side wakes once `batch` are ready for it. batch is
  /// at most (capacity + 1) / 2: both sides asleep, each waiting for blocks the other holds, would
  /// need more blocks than there are.
  Handoff(int capacity, int batch) : batch_(std::clamp(batch, 1, std::max(1, (capacity + 1) / 2))) {
    for (int i = 0; i < capacity; ++i) {
      blocks_.push_back(std::make_unique<Block>());
      free_.q.push_back(blocks_.back().get());
    }
    free_.wake_at = static_cast<std::size_t>(batch_);
  }

  /// Producer: a free block (waits for one); nullptr once stop() was called.
  Block* acquire() { return pop(free_, true); }
  /// Producer: b, filled, to the consumer; `last`: nothing follows it (a consumer waiting for
  /// a batch takes what there is).
  void publish(Block* b, bool last = false) { push(full_, b, last); }
  /// Consumer: the next full block, in the order published (waits for it); nullptr once the last
  /// one was taken (publish(b, true)): nothing would ever come.
  Block* take() { return pop(full_, false); }
  /// Consumer: b back to the producer.
  void release(Block* b) { push(free_, b, false); }
  /// The consumer takes no more (called by the consumer, so only the producer may be waiting):
  /// a producer waiting for a free block (or asking for the next) gets nullptr.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopped_ = true;
    }
    free_.cv.notify_all();
  }
  /// Times a side went to sleep for want of a block (each was woken once).
  int64_t sleeps() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return sleeps_;
  }

 private:
  struct Queue {
    std::deque<Block*> q;
    std::condition_variable cv;
    bool waiting = false;  ///< its taker sleeps until `wake_at` blocks (or `done`)
    /// batch_, but 1 for the consumer's first block: at the start it has nothing to work on,
    /// and waiting for a batch would only delay it.
    std::size_t wake_at = 1;
    bool done = false;     ///< nothing more will be pushed (the last block is in)
  };

  /// The first block of q, waiting for one; nullptr if `stoppable` and stop() was called, or if
  /// q is empty and done.
  Block* pop(Queue& q, bool stoppable) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (q.q.empty() && q.done) return nullptr;
    if (q.q.empty() && !(stoppable && stopped_)) {
      ++sleeps_;
      q.waiting = true;
      q.cv.wait(lock, [&] { return (stoppable && stopped_) || !q.waiting; });
      q.waiting = false;
    }
    if (stoppable && stopped_) return nullptr;
    Block* b = q.q.front();
    q.q.pop_front();
    q.wake_at = static_cast<std::size_t>(batch_);
    return b;
  }
  void push(Queue& q, Block* b, bool last) {
    bool wake = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      q.q.push_back(b);
      if (last) q.done = true;
      if (q.waiting && (q.q.size() >= q.wake_at || q.done)) {
        q.waiting = false;
        wake = true;
      }
    }
    if (wake) q.cv.notify_one();
  }

  const int batch_;
  std::vector<std::unique_ptr<Block>> blocks_;
  mutable std::mutex mutex_;
  Queue free_, full_;
  bool stopped_ = false;
  int64_t sleeps_ = 0;
};

}  // namespace lcmloc::replay
