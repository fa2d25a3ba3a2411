#pragma once
// A second publisher on a channel told apart from the one that feeds the fusion: lcm-logplayer
// started on the live network, a driver started twice, a second vehicle on the same segment.
// Each channel has one established stream; a message whose seq does not go on from it belongs
// to another stream. A publisher counts its seqs from 0 when it starts, so a stream that begins
// from seq 0 may be the established publisher restarted: it is taken while the established
// stream is silent. A stream that begins mid-way joined a channel someone else already feeds:
// it is held apart whether or not the established stream is silent at that moment (a sparse
// channel, such as fault markers published twice a run, is silent most of the time).
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
  /// Replaced: what was replaced was one message from mid-way, never gone on (a corrupt seq).
  bool lone = false;
  int64_t first_seq = 0, first_utime = 0;  ///< the other stream's first message (Held, Replaced)
  int64_t established_seq = 0, established_utime = 0;  ///< the established stream's last message
  bool held() const { return kind == Kind::Held; }
  /// "CH: a second publisher (first seq S at utime T) beside the established one (last seq L at
  /// utime U): its messages are held apart", or for Replaced that the new stream was taken.
  std::string describe(const std::string& channel) const;
};

/// Per channel: the established stream and at most one other. A stream begun at seq 0..kMaxAhead
/// is "from its start"; the established stream is confirmed once it is from its start or has
/// gone on (two messages). Rules for a message (seq, utime):
///  - it goes on from the established stream (seq after its last by at most kMaxAhead, or equal):
///    taken;
///  - it goes on from the other stream:
///    - the established stream is not confirmed (one message from mid-way: a corrupt seq, perhaps,
///      when the daemon started): the other replaces it;
///    - the other is from its start (a restart): taken while the established stream has not
///      published since the other began, held once it has (two publishers); when the established
///      stream stays silent for kReplaceAfter of the other's messages in a row spanning at least
///      kSilenceUs of their message time, the other replaces it (one message with a wrong time
///      cannot: a message more than 5 kSilenceUs after its stream's last time does not move that
///      stream's time);
///    - the other began mid-way (a second publisher that joined, or the same log played from
///      its middle): held, and it never replaces a confirmed stream;
///  - neither: it starts the other stream, and is taken (a corrupt seq costs nothing; what a
///    lone wrong message can do is bounded by the fusion's input checks).
/// Two publishers whose seqs interleave within kMaxAhead of each other are not told apart, and a
/// second publisher that starts from seq 0 while the established stream is silent is taken as a
/// restart until the established stream publishes again.
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
    bool from_start = false;  ///< begun at seq 0..kMaxAhead: a publisher from its start
    bool confirmed() const { return from_start || count >= 2; }
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
