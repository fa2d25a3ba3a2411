#pragma once
// Canonical ordering of incoming measurements: by utime, then by a fixed channel rank, then by
// seq. Items are held for a bounded window of message time so that a live run (where UDP may
// deliver slightly out of order) and a replay process the same sequence.
#include <algorithm>
#include <climits>
#include <cstdint>
#include <functional>
#include <tuple>
#include <utility>
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
  /// released (key <= last released), or is a duplicate key; a refused item is left untouched.
  /// An item that does not `advance` (a command) waits for the others: it does not move the
  /// newest time that releases items.
  bool push(const OrderKey& key, const T& item, bool advance = true) { return push(key, T(item), advance); }
  bool push(const OrderKey& key, T&& item, bool advance = true) {
    if (released_any_ && !(last_released_ < key)) return false;
    // Before either insert: one out of order (at equal utimes from two sources) that found the
    // storage full would otherwise grow it with the released items still in it, for good.
    compact();
    if (empty() || items_.back().first < key) {  // the usual case: in order
      items_.emplace_back(key, std::move(item));
    } else {
      const auto it = lowerBound(key);
      if (!(key < it->first)) return false;  // duplicate
      items_.emplace(it, key, std::move(item));
    }
    if (advance) newest_utime_ = std::max(newest_utime_, key.utime);
    return true;
  }

  /// Releases, in canonical order, every item older than newest - window.
  template <typename F>
  void releaseReady(F&& sink) {
    while (!empty() && items_[head_].first.utime < newest_utime_ - window_us_) pop(sink);
  }

  /// Releases everything (end of input / shutdown).
  template <typename F>
  void flush(F&& sink) {
    while (!empty()) pop(sink);
  }

  std::size_t size() const { return items_.size() - head_; }
  bool empty() const { return head_ == items_.size(); }
  bool contains(const OrderKey& key) const {
    const auto it = lowerBound(key);
    return it != items_.cend() && !(key < it->first);
  }
  /// Key of the last released item (meaningful once anything was released).
  bool releasedAny() const { return released_any_; }
  const OrderKey& lastReleased() const { return last_released_; }
  int64_t window() const { return window_us_; }

 private:
  using Item = std::pair<OrderKey, T>;
  typename std::vector<Item>::const_iterator lowerBound(const OrderKey& key) const {
    return std::lower_bound(items_.cbegin() + static_cast<std::ptrdiff_t>(head_), items_.cend(), key,
                            [](const Item& a, const OrderKey& k) { return a.first < k; });
  }
  typename std::vector<Item>::iterator lowerBound(const OrderKey& key) {
    return std::lower_bound(items_.begin() + static_cast<std::ptrdiff_t>(head_), items_.end(), key,
                            [](const Item& a, const OrderKey& k) { return a.first < k; });
  }
  /// The sink sees the item where it is stored (no move out): it must not push meanwhile. The
  /// released item is destroyed when compact() reuses its place.
  template <typename F>
  void pop(F& sink) {
    const Item& item = items_[head_++];
    last_released_ = item.first;
    released_any_ = true;
    sink(item.first, item.second);
  }
  /// Drops the released items at the front before the storage would grow: the vector's
  /// storage is reused, no allocation per item. Only when at least half of the items are
  /// released: the storage then grows to about twice the window's items and each compaction
  /// moves at most as many items as were pushed since the one before.
  void compact() {
    if (items_.size() < items_.capacity() || head_ * 2 < items_.size()) return;
    items_.erase(items_.begin(), items_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
  int64_t window_us_;
  int64_t newest_utime_ = INT64_MIN;
  bool released_any_ = false;
  OrderKey last_released_;
  /// Sorted by key from head_ on (inputs arrive nearly in order: appends); [0, head_) released.
  std::vector<Item> items_;
  std::size_t head_ = 0;
};

}  // namespace lcmloc::core
