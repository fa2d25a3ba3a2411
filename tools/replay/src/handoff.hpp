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
  Block* acquire() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return stopped_ || !free_.empty(); });
    if (stopped_) return nullptr;
    Block* b = free_.front();
    free_.pop_front();
    return b;
  }
  /// Producer: b, filled, to the consumer.
  void publish(Block* b) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      full_.push_back(b);
    }
    cv_.notify_all();
  }
  /// Consumer: the next full block, in the order published (waits for it).
  Block* take() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return !full_.empty(); });
    Block* b = full_.front();
    full_.pop_front();
    return b;
  }
  /// Consumer: b back to the producer.
  void release(Block* b) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back(b);
    }
    cv_.notify_all();
  }
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
  std::vector<std::unique_ptr<Block>> blocks_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Block*> free_, full_;
  bool stopped_ = false;
};

}  // namespace lcmloc::replay
