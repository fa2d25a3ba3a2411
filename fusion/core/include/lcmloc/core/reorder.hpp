#pragma once
// Canonical ordering of incoming measurements: by utime, then by a fixed channel rank, then by
// seq. Items are held for a bounded window of message time so that a live run (where UDP may
// deliver slightly out of order) and a replay process the same sequence.
#include <algorithm>
#include <climits>
#include <cstdint>
#include <functional>
#include <map>
#include <tuple>
#include <vector>

namespace lcmloc::core {

struct OrderKey {
  int64_t utime = 0;
  int rank = 0;     ///< fixed per channel (e.g. odometry before ruler at equal utime)
  int64_t seq = 0;
  bool operator<(const OrderKey& o) const {
    return std::tie(utime, rank, seq) < std::tie(o.utime, o.rank, o.seq);
  }
};

template <typename T>
class ReorderBuffer {
 public:
  explicit ReorderBuffer(int64_t window_us) : window_us_(window_us) {}

  /// Inserts an item. Returns false (and drops it) when it is older than what has already been
  /// released (key <= last released), or is a duplicate key.
  bool push(const OrderKey& key, T item) {
    if (released_any_ && !(last_released_ < key)) return false;
    if (items_.count(key)) return false;
    newest_utime_ = std::max(newest_utime_, key.utime);
    items_.emplace(key, std::move(item));
    return true;
  }

  /// Releases, in canonical order, every item older than newest - window.
  template <typename F>
  void releaseReady(F&& sink) {
    while (!items_.empty() && items_.begin()->first.utime < newest_utime_ - window_us_) pop(sink);
  }

  /// Releases everything (end of input / shutdown).
  template <typename F>
  void flush(F&& sink) {
    while (!items_.empty()) pop(sink);
  }

  std::size_t size() const { return items_.size(); }
  bool contains(const OrderKey& key) const { return items_.count(key) > 0; }
  /// Key of the last released item (meaningful once anything was released).
  bool releasedAny() const { return released_any_; }
  const OrderKey& lastReleased() const { return last_released_; }
  int64_t window() const { return window_us_; }

 private:
  template <typename F>
  void pop(F& sink) {
    auto it = items_.begin();
    last_released_ = it->first;
    released_any_ = true;
    OrderKey k = it->first;
    T v = std::move(it->second);
    items_.erase(it);
    sink(k, v);
  }
  int64_t window_us_;
  int64_t newest_utime_ = INT64_MIN;
  bool released_any_ = false;
  OrderKey last_released_;
  std::map<OrderKey, T> items_;
};

}  // namespace lcmloc::core
