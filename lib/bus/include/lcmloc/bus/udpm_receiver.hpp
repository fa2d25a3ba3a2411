#pragma once
// LCM's udpm:// wire protocol received on a socket of our own, in the thread that calls handle().
//
// Why not LCM's receive: LCM 1.3.1 reads the socket on a thread of its own and hands each message
// to lcm_handle() through a mutex and a notify pipe, one message per call. Under a flood (a
// sender repeating a message 100 times) that hand-over cost about 0.2 ms per message, mostly
// waiting for the other thread, and an odometry message behind the flood waited its turn: the
// fusion's POSE went silent for up to 30 ms. Here the caller drains the socket with recvmmsg and
// dispatches each message in place. Publishing stays with LCM, so the bytes on the wire are LCM's.
//
// The protocol (lcm/udpm_util.h of LCM 1.3.1), all integers big-endian:
//  - short message, one datagram: u32 magic "LC02", u32 seqno, channel (NUL-terminated), payload;
//  - fragmented message: u32 magic "LC03", u32 seqno, u32 message size, u32 fragment offset,
//    u16 fragment number, u16 fragments in the message, then the fragment's bytes; fragment 0
//    begins with the NUL-terminated channel. LCM reassembles per sender and so does this.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lcmloc::bus {

/// What a udpm:// URL says about receiving, as LCM 1.3.1 reads it.
struct UdpmAddress {
  uint32_t group = 0;   ///< multicast group, host byte order
  uint16_t port = 0;    ///< host byte order
  int recv_buf_size = 0;  ///< SO_RCVBUF to ask for (0: the kernel's default)
};

/// The group, port and receive buffer of a udpm:// URL (LCM's defaults 239.255.76.67:7667 when
/// the address is left out). nullopt when url is not udpm://, its address or port is bad, or it has
/// an option LCM 1.3.1 does not read (ttl and recv_buf_size are read; anything else leaves the
/// receive to LCM, which then reports the option itself).
std::optional<UdpmAddress> parseUdpmUrl(const std::string& url);

/// One complete message. data stays valid until the next call that adds a datagram.
struct UdpmMessage {
  std::string_view channel;
  const uint8_t* data = nullptr;
  std::size_t size = 0;
  int64_t recv_utime = 0;
};

/// Turns datagrams into messages: a short message at once, a fragmented one when its last
/// fragment is in. Pure (no socket), so the parser is unit-tested and fuzzed on bytes.
class UdpmAssembler {
 public:
  static constexpr std::size_t kMaxChannel = 63;             ///< LCM_MAX_CHANNEL_NAME_LENGTH
  static constexpr uint32_t kMaxMessage = 16u << 20;         ///< larger fragmented messages: dropped
  static constexpr std::size_t kMaxPendingBytes = 16u << 20;  ///< all senders' partial messages
  static constexpr std::size_t kMaxPendingSenders = 1000;

  /// Message: *out holds one. Partial: a fragment kept (or a duplicate, or one whose message's
  /// first fragment was missed). Ignored: a message, or the first fragment of one, on a channel
  /// no one subscribes to (as in LCM, such a message is not reassembled). Bad: not LCM's protocol.
  enum class Result { Message, Partial, Ignored, Bad };
  /// Adds one datagram from sender (any key that tells senders apart: address and port);
  /// wanted(channel) says whether anyone subscribes to the channel.
  Result add(const uint8_t* packet, std::size_t size, uint64_t sender, int64_t recv_utime,
             const std::function<bool(std::string_view)>& wanted, UdpmMessage* out);

  std::size_t pendingSenders() const { return pending_.size(); }
  std::size_t pendingBytes() const { return pending_bytes_; }

 private:
  struct Partial {
    uint32_t seqno = 0;
    std::string channel;
    std::vector<uint8_t> data;
    std::vector<bool> got;
    uint32_t remaining = 0;
    uint64_t started = 0;  ///< order of arrival, for evicting the oldest
  };
  void drop(std::map<uint64_t, Partial>::iterator it);

  std::map<uint64_t, Partial> pending_;  ///< per sender (LCM keeps one message per sender)
  std::size_t pending_bytes_ = 0;
  uint64_t arrivals_ = 0;
  std::vector<uint8_t> done_;  ///< the last reassembled message
  std::string done_channel_;
};

/// A non-blocking socket bound to the URL's port that joined its group (SO_REUSEADDR and
/// SO_TIMESTAMP as LCM sets them), read in the caller's thread.
class UdpmReceiver {
 public:
  /// Throws TransportError (transport.hpp) when the socket cannot be made or the group joined.
  explicit UdpmReceiver(const UdpmAddress& address);
  ~UdpmReceiver();
  UdpmReceiver(const UdpmReceiver&) = delete;
  UdpmReceiver& operator=(const UdpmReceiver&) = delete;

  using Wanted = std::function<bool(std::string_view)>;
  using Dispatch = std::function<void(const UdpmMessage&)>;
  /// Waits up to timeout_ms (0: no wait, < 0: for ever) for a message that wanted() accepts, as
  /// lcm_handle_timeout does, then reads what has arrived, up to max_datagrams, and dispatches
  /// every complete message that wanted() accepts. Returns the datagrams read (> 0) once a
  /// message was dispatched (with timeout_ms 0: once any datagram was read), 0 when none came in
  /// time, < 0 when interrupted by a signal.
  int handle(int timeout_ms, const Wanted& wanted, const Dispatch& dispatch, int max_datagrams = 256);

  int fd() const { return fd_; }
  int receiveBuffer() const { return rcvbuf_; }  ///< SO_RCVBUF as the kernel set it

 private:
  int readSome(const Wanted& wanted, const Dispatch& dispatch, int max_datagrams, int* dispatched);

  int fd_ = -1;
  int rcvbuf_ = 0;
  UdpmAssembler assembler_;
  struct Batch;
  std::vector<uint8_t> buffers_;
};

}  // namespace lcmloc::bus
