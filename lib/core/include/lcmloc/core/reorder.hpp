#pragma once
// Canonical ordering of incoming measurements: by utime, then by a fixed channel rank, then by
// seq. Items are held for a bounded window of message time so that a live run (where UDP may
// deliver slightly out of order) and a replay process the same sequence.
#include <algorithm>
#include <climits>
#include <cstdint>
#include <cstdlib>
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

/// Items are kept in slots that are reused: an item is moved in once (move-assigned into a free
/// slot), released where it is, and its slot taken by a later item; only the keys (small,
/// trivially copyable) are kept sorted and shifted. The slots number at most the items the
/// window held at once.
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
    // storage full would otherwise grow it with the released keys still in it, for good.
    compact();
    auto at = keys_.end();
    if (!(empty() || keys_.back().key < key)) {  // (the usual case: in order, at the end)
      at = lowerBound(key);
      if (!(key < at->key)) return false;  // duplicate
    }
    uint32_t slot;
    if (free_.empty()) {
      slot = static_cast<uint32_t>(slots_.size());
      slots_.push_back(std::move(item));
    } else {
      slot = free_.back();
      free_.pop_back();
      slots_[slot] = std::move(item);
    }
    // Written in place, field by field: a Key made first and then copied in would be read back
    // whole (wide loads) right after its fields were stored one by one, which the CPU cannot
    // forward from its store buffer: a stall of tens of cycles per item.
    Key& k = *keys_.emplace(at);
    k.key.utime = key.utime;
    k.key.rank = key.rank;
    k.key.seq = key.seq;
    k.slot = slot;
    if (advance) newest_utime_ = std::max(newest_utime_, key.utime);
    return true;
  }

  /// Releases, in canonical order, every item older than newest - window.
  template <typename F>
  void releaseReady(F&& sink) {
    while (!empty() && keys_[head_].key.utime < newest_utime_ - window_us_) pop(sink);
  }

  /// Releases the oldest item, if any (the memory bound of the caller's horizon).
  template <typename F>
  void releaseOldest(F&& sink) {
    if (!empty()) pop(sink);
  }

  /// Releases everything (end of input / shutdown).
  template <typename F>
  void flush(F&& sink) {
    while (!empty()) pop(sink);
  }

  /// f(key, item) for every item waiting, in canonical order (nothing is released).
  template <typename F>
  void forEachQueued(F&& f) const {
    for (std::size_t i = head_; i < keys_.size(); ++i) f(keys_[i].key, static_cast<const T&>(slots_[keys_[i].slot]));
  }

  std::size_t size() const { return keys_.size() - head_; }
  bool empty() const { return head_ == keys_.size(); }
  bool contains(const OrderKey& key) const {
    const auto it = lowerBound(key);
    return it != keys_.cend() && !(key < it->key);
  }
  /// Key of the last released item (meaningful once anything was released).
  bool releasedAny() const { return released_any_; }
  const OrderKey& lastReleased() const { return last_released_; }
  int64_t window() const { return window_us_; }

 private:
  struct Key {
    OrderKey key;
    uint32_t slot;
  };
  typename std::vector<Key>::const_iterator lowerBound(const OrderKey& key) const {
    return std::lower_bound(keys_.cbegin() + static_cast<std::ptrdiff_t>(head_), keys_.cend(), key,
                            [](const Key& a, const OrderKey& k) { return a.key < k; });
  }
  typename std::vector<Key>::iterator lowerBound(const OrderKey& key) {
    return std::lower_bound(keys_.begin() + static_cast<std::ptrdiff_t>(head_), keys_.end(), key,
                            [](const Key& a, const OrderKey& k) { return a.key < k; });
  }
  /// The sink sees the item in its slot: it must not push meanwhile. The slot is free again
  /// after it.
  template <typename F>
  void pop(F& sink) {
    const Key k = keys_[head_++];
    last_released_ = k.key;
    released_any_ = true;
    sink(k.key, static_cast<const T&>(slots_[k.slot]));
    free_.push_back(k.slot);
  }
  /// Drops the released keys at the front before the key storage would grow: it is reused, no
  /// allocation per item. Only when at least half of the keys are released: the storage then
  /// grows to about twice the window's items and each compaction moves at most as many keys as
  /// were pushed since the one before.
  void compact() {
    if (keys_.size() < keys_.capacity() || head_ * 2 < keys_.size()) return;
    keys_.erase(keys_.begin(), keys_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
  int64_t window_us_;
  int64_t newest_utime_ = INT64_MIN;
  bool released_any_ = false;
  OrderKey last_released_;
  /// Sorted by key from head_ on (inputs arrive nearly in order: appends); [0, head_) released.
  std::vector<Key> keys_;
  std::size_t head_ = 0;
  std::vector<T> slots_;        ///< the items, waiting or released
  std::vector<uint32_t> free_;  ///< slots whose item was released
};

}  // namespace lcmloc::core
