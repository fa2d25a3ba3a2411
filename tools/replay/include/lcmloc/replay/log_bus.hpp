#pragma once
// A bus::MessageBus over log files: subscriptions are fed from the events of an input log
// (dispatch), publications are written to an output log. The offline replay runs the fusion
// daemon's own code (fusion::FusionDaemon) on it, so the bytes it writes are the bytes the daemon
// publishes live.
//
// Output event timestamps are the message's own utime (the first field of every lcmloc type,
// bytes 8..15 of the payload after the 8-byte type fingerprint), so the output file depends on
// the messages alone: the same input and config give the same file, byte for byte.
#include <cstdint>
#include <map>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "lcmloc/replay/cache_line.hpp"
#include "lcmloc/bus/transport.hpp"

namespace lcmloc::replay {

/// The utime of an lcmloc message (big-endian int64 after the fingerprint); fallback if shorter.
int64_t messageUtime(const void* data, std::size_t size, int64_t fallback);

class LogBus : public bus::MessageBus {
 public:
  /// output empty: publications are counted and dropped. Throws std::runtime_error when the
  /// output cannot be created.
  explicit LogBus(const std::string& output);
  ~LogBus() override;

  bool publishRaw(const std::string& channel, const void* data, std::size_t size) override;
  void subscribeRaw(const std::string& channel, RawHandler handler) override;

  /// Hands one input event to every subscription whose regex matches the channel. Returns the
  /// number of handlers called (0: nobody subscribes to this channel).
  int dispatch(const std::string& channel, const void* data, std::size_t size, int64_t recv_utime);
  /// dispatch() of an event whose channel is that of the last dispatch() (the caller knows it:
  /// the channel is not looked up again).
  int dispatchAgain(const std::string& channel, const void* data, std::size_t size, int64_t recv_utime);
  /// Copies an input event to the output unchanged (timestamp: the message's utime).
  bool copy(const std::string& channel, const void* data, std::size_t size, int64_t fallback_utime);

  int64_t written() const { return written_; }
  /// What failed writing the output log ("" while every write succeeded); nothing is written
  /// after a failure.
  const std::string& writeError() const { return write_error_; }
  std::map<std::string, int64_t> writtenPerChannel() const;
  /// Writes out what is buffered and closes the output.
  void close();

 private:
  bool write(const std::string& channel, const void* data, std::size_t size, int64_t timestamp);
  int call(const std::vector<std::size_t>& handlers, const std::string& channel, const void* data, std::size_t size,
           int64_t recv_utime);
  bool writeFailed(int err);
  /// The subscriptions whose regex matches a channel other than the last one dispatched (cached
  /// per channel); it becomes the last one.
  [[gnu::noinline]] const std::vector<std::size_t>& route(const std::string& channel);

  struct Sub {
    std::regex re;
    RawHandler handler;
  };
  std::vector<Sub> subs_;
  std::map<std::string, std::vector<std::size_t>> route_;  ///< channel -> matching subs (cached)
  /// The route_ entry of the last dispatch (most events are on the channel of the event before).
  const std::string* last_channel_ = nullptr;
  const std::vector<std::size_t>* last_route_ = nullptr;
  // The above is read by the replay's reading thread for every event, what follows written by its
  // applying thread for every output: on cache lines of their own (replay::kLinePair).
  alignas(replay::kLinePair) std::unique_ptr<class LogWriter> writer_;
  int64_t written_ = 0;
  std::string write_error_;
  std::vector<std::pair<std::string, int64_t>> per_channel_;
};

}  // namespace lcmloc::replay
