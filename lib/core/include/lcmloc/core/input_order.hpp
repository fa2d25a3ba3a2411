#pragma once
// Input ordering: the time-jump guard (TimeBaseGuard) and the reorder window (ReorderBuffer)
// between the inputs as they come and the canonical order the engine processes them in: by
// utime, then by the rank of the input's kind (kCanonicalRank), then by a stable hash of its
// channel, then by seq.
#include <cstddef>
#include <cstdint>
#include <utility>

#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/reorder.hpp"
#include "lcmloc/core/time_guard.hpp"

namespace lcmloc::core {

/// The canonical key of an input.
OrderKey canonicalKey(const EngineInput& in);

class InputOrder {
 public:
  /// What the ordering hands on.
  class Client {
   public:
    virtual ~Client() = default;
    /// The next input in canonical order.
    virtual void process(const EngineInput& in) = 0;
    /// The reorder window refused in: a duplicate, or older than processed_utime, processed already.
    virtual void late(const EngineInput& in, bool duplicate, int64_t processed_utime) = 0;
    /// The window held max_queued inputs: in, the oldest, goes to process() next, before its time.
    virtual void releasedEarly(const EngineInput& in) = 0;
    /// The time-jump guard held in (ahead of, or behind, newest) and the old time base went on.
    virtual void outlier(const EngineInput& in, bool ahead, int64_t newest) = 0;
    /// A command more than the guard ahead of newest.
    virtual void commandAhead(const EngineInput& in, int64_t newest) = 0;
    /// A new time base from first on, after newest. back: time went back; everything of the old
    /// base was processed, and the client starts every part afresh (reset() included).
    virtual void timeJumped(const EngineInput& first, int64_t newest, bool back) = 0;
    /// Whether in's time moves the horizon on (releases what is older by the window). An input
    /// that does not is ordered and processed all the same, at the time the others carry.
    virtual bool carriesTime(const EngineInput& in) const {
      (void)in;
      return true;
    }
  };

  /// window_us: the horizon (EngineConfig::horizonUs()); max_jump_us: EngineConfig::max_time_jump_us;
  /// max_queued: EngineConfig::max_queued (at least 1).
  InputOrder(int64_t window_us, int64_t max_jump_us, std::size_t max_queued, Client& client)
      : window_us_(window_us), max_jump_us_(max_jump_us), max_queued_(max_queued < 1 ? 1 : max_queued),
        window_(window_us), guard_(max_jump_us), client_(client) {}
  /// No memory bound (every input held for the window).
  InputOrder(int64_t window_us, int64_t max_jump_us, Client& client)
      : InputOrder(window_us, max_jump_us, SIZE_MAX, client) {}

  /// An input as it comes (FusionEngine::push). Returns false when it was refused.
  bool push(EngineInput&& in);
  /// Everything still held is dropped, everything queued processed (end of input).
  void flush();
  /// Everything queued processed (a new time base: what came before it goes first).
  void drain();
  /// Newest message time taken (INT64_MIN: none yet, or time started over).
  int64_t newest() const { return guard_.newest(); }
  /// [us] Message time the inputs confirming a new time base span at least.
  int64_t confirmSpan() const { return guard_.confirmSpan(); }
  /// f(key, input) for every input waiting in the window, in canonical order (held ones not).
  template <typename F>
  void forEachQueued(F&& f) const { window_.forEachQueued(std::forward<F>(f)); }
  /// Inputs waiting in the window.
  std::size_t queued() const { return window_.size(); }
  /// [us] The window (the horizon).
  int64_t window() const { return window_us_; }
  std::size_t maxQueued() const { return max_queued_; }
  /// Nothing queued, held or released: time starts over.
  void reset();

 private:
  bool pushCommand(EngineInput&& in);
  /// Past the time-jump guard: into the reorder window; an input that does not `advance` (a
  /// command) does not move the window's time.
  bool take(EngineInput&& in, bool advance);

  int64_t window_us_, max_jump_us_;
  std::size_t max_queued_;
  ReorderBuffer<EngineInput> window_;
  TimeBaseGuard<EngineInput> guard_;
  Client& client_;
};

}  // namespace lcmloc::core
