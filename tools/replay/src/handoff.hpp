#pragma once
// Blocks handed from one thread (the producer) to another (the consumer) in order, at most
// `capacity` in flight; the consumer gives each block back for reuse, so nothing is allocated
// once the blocks have grown. One lock and one wake-up per block: a block carries many items.
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <vector>

namespace lcmloc::replay {

template <typename Block>
class Handoff {
 public:
  explicit Handoff(int capacity) {
    for (int i = 0; i < capacity; ++i) {
      blocks_.push_back(std::make_unique<Block>());
      free_.push_back(blocks_.back().get());
    }
  }

  /// Producer: a free block (waits for one); nullptr once stop() was called.
  Block* acquire() { return pop(free_, true); }
  /// Producer: b, filled, to the consumer.
  void publish(Block* b) { push(full_, b); }
  /// Consumer: the next full block, in the order published (waits for it).
  Block* take() { return pop(full_, false); }
  /// Consumer: b back to the producer.
  void release(Block* b) { push(free_, b); }
  /// The consumer takes no more: a producer waiting for a free block (or asking for the next)
  /// gets nullptr.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopped_ = true;
    }
    cv_.notify_all();
  }

 private:
  /// The first block of q, waiting for one; nullptr if `stoppable` and stop() was called.
  Block* pop(std::deque<Block*>& q, bool stoppable) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return (stoppable && stopped_) || !q.empty(); });
    if (stoppable && stopped_) return nullptr;
    Block* b = q.front();
    q.pop_front();
    return b;
  }
  void push(std::deque<Block*>& q, Block* b) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      q.push_back(b);
    }
    cv_.notify_all();
  }

  std::vector<std::unique_ptr<Block>> blocks_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Block*> free_, full_;
  bool stopped_ = false;
};

}  // namespace lcmloc::replay
