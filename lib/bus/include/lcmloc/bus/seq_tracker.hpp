#pragma once
// Per-channel sequence numbers of the messages: lost messages counted, a new sequence and a lone
// corrupt seq told apart from a loss.
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace lcmloc::bus {

/// What one message's seq says about its channel: `missing` messages before the one with seq
/// `before_seq`, a new sequence (`restarted`), and/or a seq that was ignored (`ignored`).
struct SeqGap {
  int64_t missing = 0;
  int64_t before_seq = 0;
  /// A new sequence, confirmed by the message after it: seq went back (from last_seq to
  /// before_seq; the sender started over) or jumped ahead by more than SeqTracker::kMaxSeqGap (a
  /// counter that started from another value). What the sender did not send meanwhile cannot be
  /// counted.
  bool restarted = false;
  int64_t last_seq = 0;
  /// The message before this one broke the sequence (its seq, ignored_seq, jumped from
  /// ignored_after) and this one (seq next_seq) did not go on from it: a lone corrupt seq (or a
  /// message out of order), ignored: no gap, no restart.
  bool ignored = false;
  int64_t ignored_seq = 0, ignored_after = 0, next_seq = 0;
  /// Messages counted as missing at the ignored seq and taken back now (SeqTracker::gaps() went
  /// down by as many, and up by `missing`): it was a small jump ahead, counted at once, and this
  /// message falls inside it.
  int64_t uncounted = 0;
  explicit operator bool() const { return missing > 0; }
  /// "KEY: N message(s) missing before seq S"
  std::string describe(const std::string& key) const;
  /// "KEY: seq went back from L to S (the sender started over?): ..." (or "jumped ahead")
  std::string describeRestart(const std::string& key) const;
  /// "KEY: seq I (after L) ignored: the next message (seq N) did not go on from it (a corrupt seq?)"
  std::string describeIgnored(const std::string& key) const;
};

/// Per-channel sequence-gap counter that counts lost messages, not corruption:
///  - seq = last + 1 + n with n <= kMaxUnconfirmedGap: n messages missing, counted at once (and
///    taken back, `uncounted`, when the next message falls inside the jump: 100, 108, 101);
///  - a larger jump ahead, or any step back, is taken only when the next message goes on from it
///    (its seq is the jumped one + 1): then a jump of up to kMaxSeqGap counts its missing
///    messages, and a step back or a larger jump is a new sequence (`restarted`, nothing counted);
///    otherwise the lone seq is ignored (`ignored`, counted by ignored()) and the sequence goes on
///    from the last seq taken, the ignored message standing for one of the numbers in between.
///    One corrupt seq thus costs nothing, wherever its bits flipped;
///  - a duplicate (seq = last) counts nothing.
/// A big loss at the very end of a stream (no message after the jump) is not counted.
class SeqTracker {
 public:
  static constexpr int64_t kMaxUnconfirmedGap = 1000;
  static constexpr int64_t kMaxSeqGap = int64_t{1} << 24;  ///< 16.8 million: 46 h of a 100 Hz channel
  /// The messages missing before this one (missing = 0 in order).
  SeqGap observe(const std::string& key, int64_t seq);
  /// observe() of the usual message, inline: true when seq follows on the key observed last (the
  /// message is taken, nothing to report); false, nothing changed, otherwise: observe() it then.
  bool follows(const std::string& key, int64_t seq) {
    return last_ < entries_.size() && entries_[last_].first == key && followsLast(seq);
  }
  /// follows() for a caller that knows the key is the one observed last (the one of its
  /// previous observe() or follows()): no comparison of the key.
  bool followsLast(int64_t seq) {
    if (last_ >= entries_.size()) return false;
    Entry& e = entries_[last_].second;
    if (e.pending || e.last == INT64_MAX || seq != e.last + 1) return false;
    e.jump_missing = 0;  // (as observe() takes it)
    e.last = seq;
    return true;
  }
  int64_t gaps() const { return total_; }
  int64_t gaps(const std::string& key) const;
  /// Seqs ignored as lone outliers (SeqGap::ignored).
  int64_t ignored() const { return ignored_; }
  int64_t ignored(const std::string& key) const;
  /// Keys seen (a caller that must bound its memory stops giving new keys at some size()).
  std::size_t size() const { return entries_.size(); }
  bool tracks(const std::string& key) const { return index_.count(key) > 0; }
 private:
  struct Entry {
    int64_t last = 0, gaps = 0, ignored = 0;
    bool pending = false;  ///< `candidate` broke the sequence: waiting for the next message
    int64_t candidate = 0;
    int64_t jump_missing = 0, before_jump = 0;  ///< the last seq was a small jump, counted at once
  };
  std::vector<std::pair<std::string, Entry>> entries_;
  std::unordered_map<std::string, std::size_t> index_;
  std::size_t last_ = 0;  ///< entry of the last key observed
  int64_t total_ = 0, ignored_ = 0;
};

}  // namespace lcmloc::bus
