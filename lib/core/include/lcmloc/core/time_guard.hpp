#pragma once
// Time-base guard: decides, input by input, whether message time goes on, jumped for one input
// (a corrupt utime: dropped), or jumped for good (a new time base: a source that resumed after a
// pause, or one that started over, such as a restarted simulator or a log played again). Used by
// the fusion engine and by the sensor drivers' GROUND_TRUTH input. Middleware free.
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace lcmloc::core {

/// Consecutive inputs beyond the guard that confirm a new time base (at least; see
/// kTimeJumpConfirmSpanUs).
inline constexpr int kTimeJumpConfirm = 3;
/// [us] Message time the consecutive inputs of a new time base must span, too (at most half the
/// guard's max_jump): a count alone let one fast channel with a faulty clock take the time base
/// over, three of its inputs coming before the next of a slower channel (an IMU at 400 Hz with
/// its clock 1e12 us ahead, before the next 100 Hz ODOMETRY); the other channels' inputs on the
/// old time base, inside the span, drop such outliers.
inline constexpr int64_t kTimeJumpConfirmSpanUs = 200000;

/// a - b > limit (limit >= 0), also where a - b does not fit in 64 bits (corrupt utimes).
inline bool apartBy(int64_t a, int64_t b, int64_t limit) {
  int64_t d;
  if (__builtin_sub_overflow(a, b, &d)) return a > b;
  return d > limit;
}

/// a - b [us], saturated to the int64 range where it does not fit (corrupt utimes).
inline int64_t timeApart(int64_t a, int64_t b) {
  int64_t d;
  if (__builtin_sub_overflow(a, b, &d)) return a > b ? INT64_MAX : INT64_MIN;
  return d;
}

/// a - b [s] (any two utimes: in doubles, never overflowing).
inline double secondsBetween(int64_t a, int64_t b) { return (static_cast<double>(a) - static_cast<double>(b)) * 1e-6; }

/// Whole seconds from b to a (a >= b), saturated where the difference does not fit.
inline int64_t secondsApart(int64_t a, int64_t b) {
  int64_t d;
  return __builtin_sub_overflow(a, b, &d) ? INT64_MAX / 1000000 : d / 1000000;
}

/// An input whose time is more than max_jump_us ahead of, or behind, the newest time taken so
/// far is held. Consecutive held inputs on the same side, within max_jump_us of each other, confirm
/// a new time base once they are kTimeJumpConfirm or more and span kTimeJumpConfirmSpanUs (or
/// max_jump_us / 2, the smaller) of message time; an input of the old time base drops the held
/// ones as outliers. max_jump_us <= 0: off (every input is taken).
template <typename T>
class TimeBaseGuard {
 public:
  enum Side { kBack = -1, kAhead = 1 };

  explicit TimeBaseGuard(int64_t max_jump_us)
      : max_jump_(max_jump_us), confirm_span_(std::min(kTimeJumpConfirmSpanUs, max_jump_us / 2)) {}

  /// Offers an input with message time utime. Calls, in this order: drop(held, side, newest) for
  /// each held input that turned out an outlier; confirm(side, first, newest) when this input
  /// confirms a new time base (first: the first input of it); take(input) for each input to take
  /// now (this one, or the held ones with it, in order). take returns whether the input was
  /// taken; the caller reports took() for each input it took. Returns false when take refused
  /// this input (or one of the held ones it confirmed), true otherwise (also when held).
  template <typename Take, typename Drop, typename Confirm>
  bool offer(T&& in, int64_t utime, Take&& take, Drop&& drop, Confirm&& confirm) {
    int side = 0;
    if (max_jump_ > 0 && newest_ != INT64_MIN)
      side = apartBy(utime, newest_, max_jump_) ? kAhead : apartBy(newest_, utime, max_jump_) ? kBack : 0;
    if (side == 0) {
      if (!held_.empty()) dropHeld(drop);  // the old time base goes on: they were outliers
      return take(std::move(in));
    }
    return hold(std::move(in), utime, side, take, drop, confirm);
  }

  /// The caller took an input with message time utime.
  void took(int64_t utime) {
    if (utime > newest_) newest_ = utime;
  }
  /// Drops what is held (end of input): drop(held, side, newest) each.
  template <typename Drop>
  void flush(Drop&& drop) {
    dropHeld(drop);
  }
  /// [us] Message time the inputs confirming a new time base span at least.
  int64_t confirmSpan() const { return confirm_span_; }
  /// Newest message time taken (INT64_MIN: none yet, or time started over).
  int64_t newest() const { return newest_; }
  /// Nothing taken or held: time starts over (also from within confirm, for a time base behind).
  void reset() {
    newest_ = INT64_MIN;
    held_.clear();
    held_utime_ = 0;
    side_ = kAhead;
  }

 private:
  /// offer() of an input beyond the guard (side): held, or confirming a new time base.
  template <typename Take, typename Drop, typename Confirm>
  [[gnu::noinline]] bool hold(T&& in, int64_t utime, int side, Take& take, Drop& drop, Confirm& confirm) {
    if (!held_.empty() && (side != side_ || apartBy(utime, held_utime_, max_jump_) ||
                           apartBy(held_utime_, utime, max_jump_)))
      dropHeld(drop);
    if (held_.empty()) held_utime_ = utime;
    side_ = static_cast<Side>(side);
    held_.push_back(std::move(in));
    if (static_cast<int>(held_.size()) < kTimeJumpConfirm) return true;
    // (within max_jump_ of the first held one, checked above: no overflow)
    if ((utime > held_utime_ ? utime - held_utime_ : held_utime_ - utime) < confirm_span_) return true;
    std::vector<T> confirmed = std::move(held_);
    held_.clear();
    confirm(side_, static_cast<const T&>(confirmed.front()), newest_);
    if (side_ == kBack) newest_ = INT64_MIN;  // time starts over
    bool all = true;
    for (auto& c : confirmed) all = take(std::move(c)) && all;
    return all;
  }

  template <typename Drop>
  void dropHeld(Drop& drop) {
    for (const auto& h : held_) drop(h, side_, newest_);
    held_.clear();
  }

  int64_t max_jump_;
  int64_t confirm_span_;  ///< kTimeJumpConfirmSpanUs, at most max_jump_ / 2
  int64_t newest_ = INT64_MIN;
  std::vector<T> held_;
  int64_t held_utime_ = 0;  ///< message time of the first held input
  Side side_ = kAhead;
};

}  // namespace lcmloc::core
