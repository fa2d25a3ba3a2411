#include "lcmloc/core/input_order.hpp"

#include <string>

namespace lcmloc::core {
namespace {

/// FNV-1a: a hash that is the same on every run and machine (std::hash is not guaranteed to be).
uint32_t stableHash(const std::string& s) {
  uint32_t h = 2166136261u;
  for (unsigned char c : s) h = (h ^ c) * 16777619u;
  return h;
}

}  // namespace

OrderKey canonicalKey(const EngineInput& in) {
  return OrderKey{in.utime, canonicalRank(in) * 1024 + static_cast<int>(stableHash(in.channel) % 1024), in.seq};
}

bool InputOrder::push(EngineInput&& in) {
  if (std::holds_alternative<ControlCommand>(in.payload)) return pushCommand(std::move(in));
  const int64_t utime = in.utime;
  return guard_.offer(
      std::move(in), utime,
      [this](EngineInput&& e) {
        const bool advance = client_.carriesTime(e);
        return take(std::move(e), advance);
      },
      [this](const EngineInput& s, int side, int64_t newest) { client_.outlier(s, side > 0, newest); },
      [this](int side, const EngineInput& first, int64_t newest) {
        if (side < 0) drain();
        client_.timeJumped(first, newest, side < 0);
      });
}

bool InputOrder::pushCommand(EngineInput&& in) {
  // A command waits for the sensors' time, it never makes it: it neither releases the inputs
  // before it nor takes part in the time-jump guard (commands sent at once by several tools
  // each one reorder window after the newest answer would otherwise carry the time ahead of the
  // sensors, whose inputs then came too late). One beyond the guard would wait for a time that
  // may never come: refused.
  const int64_t newest = guard_.newest();
  if (max_jump_us_ > 0 && newest != INT64_MIN && apartBy(in.utime, newest, max_jump_us_)) {
    client_.commandAhead(in, newest);
    return false;
  }
  return take(std::move(in), false);
}

bool InputOrder::take(EngineInput&& in, bool advance) {
  const OrderKey key = canonicalKey(in);
  if (!window_.push(key, std::move(in), advance)) {  // refused: `in` is untouched
    const bool duplicate = window_.contains(key);
    client_.late(in, duplicate, window_.lastReleased().utime);
    return false;
  }
  if (advance) {
    guard_.took(key.utime);
    window_.releaseReady([this](const OrderKey&, const EngineInput& e) { client_.process(e); });
  }
  while (window_.size() > max_queued_)  // the memory bound: the oldest goes now, said
    window_.releaseOldest([this](const OrderKey&, const EngineInput& e) {
      client_.releasedEarly(e);
      client_.process(e);
    });
  return true;
}

void InputOrder::flush() {
  guard_.flush([this](const EngineInput& s, int side, int64_t newest) { client_.outlier(s, side > 0, newest); });
  drain();
}

void InputOrder::drain() {
  window_.flush([this](const OrderKey&, const EngineInput& e) { client_.process(e); });
}

void InputOrder::reset() {
  window_ = ReorderBuffer<EngineInput>(window_us_);
  guard_.reset();
}

}  // namespace lcmloc::core
