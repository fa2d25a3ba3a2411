#pragma once
// MemoryBus: a MessageBus in memory, for unit tests of code written against the MessageBus seam
// (the fusion daemon, the logger) without sockets; after Drake's DrakeMockLcm.
//  - publishRaw / publish record the message (published()) and queue it for delivery;
//    inject() queues bytes as if another process had sent them (an undecodable message, a
//    foreign POSE) without recording them as published.
//  - Delivery is explicit: handle() hands the oldest queued message to every subscription
//    whose channel regex matches, deliverAll() until the queue is empty. A handler is therefore
//    never called from inside publish(): as over LCM, the code under test finishes what it is
//    doing before its own messages (or a test's) come back, and a test decides when they do.
//  - Channels match as LCM matches them: the subscription's channel is a POSIX extended regex,
//    implicitly surrounded by ^ and $ (so "A|B" is "^A" or "B$": group alternatives).
//  - Subscribers receive their own publications (LCM's loopback does the same).
#include <cstdint>
#include <deque>
#include <memory>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include "lcmloc/bus/transport.hpp"

namespace lcmloc::bus {

class MemoryBus : public MessageBus {
 public:
  struct Message {
    std::string channel;
    std::vector<uint8_t> data;
    int64_t recv_utime = 0;
  };

  MemoryBus() = default;
  MemoryBus(const MemoryBus&) = delete;
  MemoryBus& operator=(const MemoryBus&) = delete;

  bool publishRaw(const std::string& channel, const void* data, std::size_t size) override;
  /// Throws TransportError when channel is not a valid regex (as Bus does).
  void subscribeRaw(const std::string& channel, RawHandler handler) override;

  /// Delivers the oldest queued message to every matching subscription: 1, or 0 when nothing is
  /// queued (nothing can arrive while it would wait: timeout_ms is not waited).
  int handle(int timeout_ms = 0) override;
  /// Delivers until nothing is queued, messages the handlers publish meanwhile included; returns
  /// how many were delivered. Throws std::runtime_error after max_messages (handlers that keep
  /// publishing to each other).
  std::size_t deliverAll(std::size_t max_messages = 10000000);

  /// Queues raw bytes on channel as another publisher's message (not recorded in published()).
  void inject(const std::string& channel, std::vector<uint8_t> bytes);
  template <typename T>
  void inject(const std::string& channel, const T& msg) {
    inject(channel, encode(msg));
  }

  /// Every message published through this bus, in order (injected ones are not).
  const std::vector<Message>& published() const { return published_; }
  /// Those published on exactly this channel.
  std::vector<Message> published(const std::string& channel) const;
  /// Those published on channel, decoded as T; throws std::runtime_error for one that is not a T.
  template <typename T>
  std::vector<T> decoded(const std::string& channel) const {
    std::vector<T> out;
    for (const auto& m : published(channel)) {
      T msg;
      if (decodeMessage(msg, m.data.data(), m.data.size()) < 0)
        throw std::runtime_error("a message on " + channel + " is not a " + T::getTypeName());
      out.push_back(std::move(msg));
    }
    return out;
  }
  void clearPublished() { published_.clear(); }

  /// Messages waiting for handle().
  std::size_t queued() const { return queue_.size(); }
  /// The recv_utime handed to the handlers of the messages queued from now on (default 0).
  void setRecvUtime(int64_t utime) { recv_utime_ = utime; }
  /// How many subscriptions match channel.
  int subscribers(const std::string& channel) const;

  template <typename T>
  static std::vector<uint8_t> encode(const T& msg) {
    std::vector<uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
    if (encodeMessage(msg, bytes.data(), bytes.size()) < 0)
      throw std::runtime_error(std::string("cannot encode a ") + T::getTypeName());
    return bytes;
  }

 private:
  struct Sub {
    std::regex re;
    RawHandler handler;
  };
  std::vector<std::unique_ptr<Sub>> subs_;
  std::deque<Message> queue_;
  std::vector<Message> published_;
  int64_t recv_utime_ = 0;
};

}  // namespace lcmloc::bus
