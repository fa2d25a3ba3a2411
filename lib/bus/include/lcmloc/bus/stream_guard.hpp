#pragma once
// A second publisher on a channel told apart from the one that feeds the fusion: lcm-logplayer
// started on the live network, a driver started twice, a second vehicle on the same segment.
// Each channel has one established stream; a message whose seq does not go on from it belongs
// to another stream. Once the established stream has published since the other began, the
// other's messages are held apart; a publisher that restarts (its old stream silent) is taken.
#include <cstdint>
#include <string>
#include <unordered_map>

namespace lcmloc::bus {

struct StreamVerdict {
  enum class Kind : uint8_t {
    Taken,     ///< the established stream's, or another's while the established one is silent
    Held,      ///< another publisher's while the established stream goes on: not for the fusion
    Replaced,  ///< the established stream was silent for StreamGuard::kSilenceUs: this one replaces it
  };
  Kind kind = Kind::Taken;
  /// Held: the first message held of that stream: report it once.
  bool detected = false;
  int64_t first_seq = 0, first_utime = 0;  ///< the other stream's first message (Held, Replaced)
  int64_t established_seq = 0, established_utime = 0;  ///< the established stream's last message
  bool held() const { return kind == Kind::Held; }
  /// "CH: a second publisher (first seq S at utime T) while the established one goes on (seq L
  /// at utime U): its messages are held apart", or for Replaced that the new stream was taken.
  std::string describe(const std::string& channel) const;
};

/// Per channel: the established stream and at most one other. Rules for a message (seq, utime):
///  - it goes on from the established stream (seq after its last by at most kMaxAhead, or equal):
///    taken;
///  - it goes on from the other stream: taken while the established stream has not published
///    since the other began (a restarted publisher, a lone corrupt seq), held once it has (two
///    publishers); when the established stream stays silent for kReplaceAfter of the other's
///    messages in a row spanning at least kSilenceUs of their message time, the other replaces
///    it (one message with a wrong time cannot: a message more than 5 kSilenceUs after its
///    stream's last time does not move that stream's time);
///  - neither: it starts the other stream, and is taken (a corrupt seq costs nothing; what a
///    lone wrong message can do is bounded by the fusion's input checks).
/// Two publishers whose seqs interleave within kMaxAhead of each other are not told apart.
class StreamGuard {
 public:
  static constexpr int64_t kMaxAhead = 1000;          ///< as SeqTracker::kMaxUnconfirmedGap
  static constexpr int64_t kSilenceUs = 2'000'000;    ///< 2 s
  static constexpr int64_t kReplaceAfter = 10;        ///< messages
  StreamVerdict observe(const std::string& channel, int64_t seq, int64_t utime);
  /// Other publishers found (one per detection), and their messages held.
  int64_t detections() const { return detections_; }
  int64_t held() const { return held_; }

 private:
  struct Stream {
    int64_t first_seq = 0, first_utime = 0, last_seq = 0, last_utime = 0;
    int64_t count = 0;
  };
  struct Channel {
    Stream est, other;
    bool has_other = false, reported = false;
    int64_t est_since_other = 0;  ///< established messages since the other stream began
    int64_t other_mark = 0;       ///< the other's last utime when the established one last published
    int64_t other_since_mark = 0; ///< the other's messages since then
  };
  std::unordered_map<std::string, Channel> channels_;
  int64_t detections_ = 0, held_ = 0;
};

}  // namespace lcmloc::bus
