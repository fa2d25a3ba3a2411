#include "lcmloc/bus/seq_tracker.hpp"

#include <algorithm>

namespace lcmloc::bus {

SeqGap SeqTracker::observe(const std::string& key, int64_t seq) {
  // Most messages come on the channel of the message before: try that entry first.
  std::size_t i = last_;
  if (!(i < entries_.size() && entries_[i].first == key)) {
    const auto found = index_.find(key);
    if (found == index_.end()) {
      index_.emplace(key, entries_.size());
      entries_.push_back({key, Entry{seq}});
      last_ = entries_.size() - 1;
      SeqGap first;
      first.before_seq = first.last_seq = seq;
      return first;
    }
    i = found->second;
  }
  last_ = i;
  Entry& e = entries_[i].second;
  SeqGap gap;
  gap.before_seq = seq;
  gap.last_seq = e.last;
  if (!e.pending && e.last != INT64_MAX && seq == e.last + 1) {  // in order: the usual case
    e.jump_missing = 0;
    e.last = seq;
    return gap;
  }
  // The seq `outlier` (after `after`) broke the sequence and this message did not go on from it.
  auto ignore = [&](int64_t outlier, int64_t after) {
    gap.ignored = true;
    gap.ignored_seq = outlier;
    gap.ignored_after = after;
    gap.next_seq = seq;
    ++e.ignored;
    ++ignored_;
  };
  if (e.jump_missing > 0) {
    const int64_t counted = e.jump_missing;
    e.jump_missing = 0;
    if (e.before_jump < seq && seq < e.last) {
      // This one falls inside the small jump before (100, 108, 101): the jumped seq was a lone
      // outlier. What it counted is taken back, and the messages between the seq before it and this
      // one counted, but for one: the outlier's own.
      e.gaps -= counted;
      total_ -= counted;
      gap.uncounted = counted;
      gap.missing = std::max<int64_t>(0, seq - e.before_jump - 2);
      e.gaps += gap.missing;
      total_ += gap.missing;
      ignore(e.last, e.before_jump);
      gap.last_seq = e.before_jump;
      e.last = seq;
      return gap;
    }
  }
  if (e.pending) {
    if (seq == e.candidate) return gap;  // the jumped message again: still waiting
    e.pending = false;
    int64_t next = 0;
    if (!__builtin_add_overflow(e.candidate, 1, &next) && seq == next) {
      // Confirmed: the sender goes on from the jumped seq.
      int64_t step = 0;
      gap.before_seq = e.candidate;
      if (!__builtin_sub_overflow(e.candidate, e.last, &step) && step > 1 && step - 1 <= kMaxSeqGap) {
        gap.missing = step - 1;
        e.gaps += gap.missing;
        total_ += gap.missing;
      } else {
        gap.restarted = true;  // went back, or jumped beyond any plausible loss: a new sequence
      }
      e.last = seq;
      return gap;
    }
    // Not confirmed: a lone outlier. The sequence goes on from the last seq taken.
    ignore(e.candidate, e.last);
  }
  int64_t step = 0;
  if (__builtin_sub_overflow(seq, e.last, &step) || step < 0 || step - 1 > kMaxUnconfirmedGap) {
    e.pending = true;  // a step back or a big jump: taken when the next message goes on from it
    e.candidate = seq;
    return gap;
  }
  if (step > 1 + gap.ignored) {
    gap.missing = step - 1 - gap.ignored;  // (a message with a seq ignored stood for one of the numbers)
    e.gaps += gap.missing;
    total_ += gap.missing;
    e.jump_missing = gap.missing;
    e.before_jump = e.last;
  }
  e.last = seq;
  return gap;
}

std::string SeqGap::describeRestart(const std::string& key) const {
  const bool back = before_seq < last_seq;
  return key + ": seq " + (back ? "went back" : "jumped ahead") + " from " + std::to_string(last_seq) + " to " +
         std::to_string(before_seq) + (back ? " (the sender started over?)" : " (a new sequence, not lost messages)") +
         ": messages it did not send meanwhile are not counted";
}

std::string SeqGap::describe(const std::string& key) const {
  return key + ": " + std::to_string(missing) + " message(s) missing before seq " + std::to_string(before_seq);
}

std::string SeqGap::describeIgnored(const std::string& key) const {
  return key + ": seq " + std::to_string(ignored_seq) + " (after " + std::to_string(ignored_after) +
         ") ignored: the next message (seq " + std::to_string(next_seq) +
         ") did not go on from it (a corrupt seq, or a message out of order); not counted as a gap" +
         (uncounted > 0 ? " (the " + std::to_string(uncounted) + " message(s) counted missing before it are taken back)"
                        : std::string());
}

int64_t SeqTracker::gaps(const std::string& key) const {
  const auto it = index_.find(key);
  return it == index_.end() ? 0 : entries_[it->second].second.gaps;
}

int64_t SeqTracker::ignored(const std::string& key) const {
  const auto it = index_.find(key);
  return it == index_.end() ? 0 : entries_[it->second].second.ignored;
}

}  // namespace lcmloc::bus
