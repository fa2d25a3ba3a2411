#pragma once
// A thin typed adapter over lcm::LCM (after Drake's Publish<T> / Subscribe<T>).
//  - Bus(url) throws TransportError when LCM cannot start (checks good() AND getFileno() >= 0).
//  - subscribe<T>(channel, handler): handler(channel, msg, recv_utime). Payloads are decoded here
//    so an undecodable message is caught, counted and logged once per channel (never a crash);
//    an optional on_error callback sees every one.
//  - every subscription queue is unbounded (LCM's default of 30 drops bursts).
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/bus/udpm_receiver.hpp"

namespace lcmloc::bus {

class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Default URL: $LCM_DEFAULT_URL, else loopback-friendly udpm with a 4 MB receive buffer.
std::string defaultLcmUrl();

/// url with "recv_buf_size=<bytes>" added when it is a udpm:// URL without one; any other URL,
/// one that sets recv_buf_size, or bytes <= 0: url unchanged. LCM 1.3.1 sets the socket's
/// SO_RCVBUF to it, which the kernel caps at net.core.rmem_max (LCM then warns on stderr).
std::string withReceiveBuffer(const std::string& url, int bytes);
/// The recv_buf_size a udpm:// URL sets (0 when none or not udpm).
long long receiveBufferOf(const std::string& url);
/// The value of option key in the URL's query ("udpm://...?ttl=1&..."); nullopt when absent.
std::optional<std::string> urlOption(const std::string& url, const std::string& key);
/// The kernel's net.core.rmem_max [bytes]: the largest SO_RCVBUF a process without
/// CAP_NET_ADMIN gets (-1 when it cannot be read), read from path.
long long kernelRmemMax(const std::string& path = "/proc/sys/net/core/rmem_max");

/// msg.decode(data, 0, size) with lcm-gen's field helpers inlined into it. Without this GCC
/// calls its big-endian helper once per field (out of line, a byte at a time): at 100 Hz
/// odometry that cost more than reading the event from the file (lcmloc-replay --bench).
template <typename T>
[[gnu::flatten]] inline int decodeMessage(T& msg, const uint8_t* data, std::size_t size) {
  return msg.decode(data, 0, static_cast<int>(size));
}

/// msg.encode(data, 0, size), its field helpers inlined likewise.
template <typename T>
[[gnu::flatten]] inline int encodeMessage(const T& msg, uint8_t* data, std::size_t size) {
  return msg.encode(data, 0, static_cast<int>(size));
}

/// Typed publish/subscribe over any raw message transport: LCM (Bus) live, a log file for the
/// offline replay (lcmloc::replay::LogBus), memory in unit tests (MemoryBus, memory_bus.hpp).
/// Code written against MessageBus (the fusion daemon) therefore publishes byte-identical
/// messages whichever transport carries them.
class MessageBus {
 public:
  /// Raw handler: (channel, payload, size, recv_utime).
  using RawHandler = std::function<void(const std::string&, const uint8_t*, std::size_t, int64_t)>;
  /// Called for each undecodable message: (channel, reason).
  using ErrorHandler = std::function<void(const std::string&, const std::string&)>;

  virtual ~MessageBus() = default;

  /// Encodes and publishes; returns false (and counts/logs once) on failure.
  template <typename T>
  bool publish(const std::string& channel, const T& msg) {
    // One encode buffer per thread, reused (no allocation per message once it has grown).
    thread_local std::vector<uint8_t> buf;
    const auto size = static_cast<std::size_t>(msg.getEncodedSize());
    if (buf.size() < size) buf.resize(size);
    if (encodeMessage(msg, buf.data(), size) < 0) return publishFailed(channel, "encode");
    return publishRaw(channel, buf.data(), size);
  }
  virtual bool publishRaw(const std::string& channel, const void* data, std::size_t size) = 0;

  /// Typed subscription; channel is an LCM regex. handler(channel, const T& msg, recv_utime): any
  /// callable, kept as it is inside the raw handler (a lambda is called inline there, not through
  /// a second std::function per message).
  template <typename T, typename Handler>
  void subscribe(const std::string& channel, Handler handler, ErrorHandler on_error = nullptr) {
    subscribeRaw(
        channel,
        [this, handler = std::move(handler), on_error = std::move(on_error), msg = T()](
            const std::string& ch, const uint8_t* data, std::size_t size, int64_t recv_utime) mutable {
          // msg: decoded into again and again (every field is written; its arrays keep their
          // storage), not made anew per message.
          const char* array = nullptr;  // (the reason is built only for a message that fails)
          try {
            if (decodeMessage(msg, data, size) >= 0) {
              handler(ch, msg, recv_utime);
              return;
            }
          } catch (const std::bad_alloc&) {
            array = ": absurd array length";
          } catch (const std::length_error&) {
            array = ": negative array length";
          }
          const std::string why = "cannot decode " + std::string(T::getTypeName()) +
                                  (array ? std::string(array)
                                         : " (" + std::to_string(size) + " bytes; wrong type or corrupt)");
          decodeFailed(ch, why);
          if (on_error) on_error(ch, why);
        });
  }
  virtual void subscribeRaw(const std::string& channel, RawHandler handler) = 0;

  /// Waits up to timeout_ms for messages and dispatches them (Drake's HandleSubscriptions). >0
  /// handled, 0 timeout, <0 error (e.g. interrupted by a signal). A transport fed from outside
  /// (the replay's LogBus, whose reader dispatches) has nothing to wait for: 0.
  virtual int handle(int timeout_ms) {
    (void)timeout_ms;
    return 0;
  }
  /// Handles what has already arrived, for at most max_ms of wall time (a sender flooding the
  /// bus must not keep a stopping process from stopping). Returns false when it stopped at that
  /// limit with messages still coming in.
  bool drain(int max_ms = 1000);

  int64_t decodeErrors() const;
  int64_t decodeErrors(const std::string& channel) const;
  int64_t publishErrors() const { return publish_errors_; }

 protected:
  bool publishFailed(const std::string& channel, const char* what);
  void decodeFailed(const std::string& channel, const std::string& why);

 private:
  std::map<std::string, int64_t> decode_errors_;
  std::map<std::string, bool> publish_error_logged_;
  int64_t publish_errors_ = 0;
};

/// The LCM transport. Publishing is LCM's. On a udpm:// URL the receive is our own
/// (UdpmReceiver, udpm_receiver.hpp: the socket drained in the thread that calls handle()),
/// unless LCMLOC_LCM_RECEIVE=lcm is set in the environment; on any other URL it is LCM's.
class Bus : public MessageBus {
 public:
  explicit Bus(const std::string& url);
  ~Bus() override;
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  const std::string& url() const { return url_; }

  bool publishRaw(const std::string& channel, const void* data, std::size_t size) override;
  void subscribeRaw(const std::string& channel, RawHandler handler) override;

  int handle(int timeout_ms) override;

  /// True when this bus receives on its own socket rather than through LCM's receive thread.
  bool ownReceive() const { return own_.has_value(); }

 private:
  struct Sub;
  struct Own;

  void selfTest();
  bool wanted(std::string_view channel);

  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Sub>> subs_;
  std::optional<UdpmAddress> own_;
  std::unique_ptr<Own> rx_;
};

/// Wall clock in microseconds since the epoch (heartbeats, log timestamps; never fusion logic).
int64_t wallMicros();

}  // namespace lcmloc::bus
