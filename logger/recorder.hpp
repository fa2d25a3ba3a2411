#pragma once
// lcmloc-logger's behaviour over any bus::MessageBus (the logger runs it over LCM, its unit
// tests over the MemoryBus): the subscription only enqueues into a LogWriter (log_writer.hpp),
// which writes on its own thread, rotating by size, by time and on request (SIGHUP). Per-channel
// accounting from the messages' seq: upstream gaps apart from the logger's own drops (a full
// queue: counted per channel, never silent), published on the status channel (logger_status_t)
// every status period and at the stop, and summed up in the log at the end (for at most
// logger::kMaxChannels channels; the rest are counted as one bucket). A new file that cannot be
// opened is reported (state "rotate_failed", heartbeat counter) while recording goes on into the
// current file. Channel and process names from the bus are printed with their control
// characters as '?'.
#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/log_throttle.hpp"
#include "lcmloc/bus/seq_tracker.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/logio/log_writer.hpp"

namespace lcmloc::logger {

struct RecorderOptions {
  std::string regex = ".*";          ///< LCM channel regex of what is recorded (channelRegex)
  std::string status_channel;        ///< logger_status_t published here ("" = none)
  double status_period = 1.0;        ///< [s, wall]
  std::string heartbeat_channel = "HEARTBEAT";
  WriterOptions writer;
};

/// The command line of lcmloc-logger beyond the common options (< 0: not given).
struct LoggerFlags {
  std::string output;
  std::vector<std::string> channels;
  double max_mb = -1, max_seconds = -1, flush_period = -1;
  bool overwrite = false;
};
void addLoggerFlags(CLI::App& app, LoggerFlags& flags);
/// The recorder's options from the configuration and the flags (which win). Throws
/// app::ConfigError for an output that is a directory or a channel regex that does not compile.
RecorderOptions recorderOptions(const app::SystemConfig& cfg, const LoggerFlags& flags);

/// One regex for LCM: empty = every channel. LCM anchors it as ^...$, which binds only the
/// first and the last alternative of A|B: the alternation is grouped, ((A)|(B)).
std::string channelRegex(const std::vector<std::string>& regexes);

/// Sizes the receive buffer of every UDP socket LCM opened (LCM 1.3.1 hides its socket, so they
/// are found among our file descriptors) to at least bytes: SO_RCVBUF (capped by the kernel at
/// net.core.rmem_max), then SO_RCVBUFFORCE (allowed with CAP_NET_ADMIN). Says what it got.
void sizeReceiveBuffer(const std::string& url, int bytes);

struct ChannelStats {
  int64_t received = 0, gaps = 0, dropped = 0, ignored = 0;
};

class Recorder {
 public:
  /// Opens the first file (throws std::runtime_error when it cannot) and subscribes to opts.regex.
  Recorder(RecorderOptions opts, bus::MessageBus& bus);
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// One turn of the process loop: the heartbeat and the status when due, then bus.handle(
  /// timeout_ms). False once the writer failed (a full disk): the loop ends.
  bool step(int timeout_ms);
  /// Starts a new file after what is queued now (SIGHUP).
  void requestRotate();
  /// The stop: takes what already arrived (for at most a second), publishes the heartbeat
  /// "stopping" and the last status; when the status channel is recorded, waits (at most half
  /// a second) for that status to come back, so the log ends with it; closes the file and logs
  /// the summary. Returns the exit code (1 after a write error).
  int finish();

  int64_t received() const { return received_; }
  /// Per channel (at most kMaxChannels) and, for the others together, under kOtherChannels.
  std::vector<std::pair<std::string, ChannelStats>> channels() const;
  int64_t gaps() const { return gaps_.gaps(); }
  WriterStats writerStats() const { return writer_.stats(); }
  std::vector<std::string> files() const { return writer_.files(); }
  app::Heartbeat::Counters counters() const;

 private:
  void onMessage(const std::string& ch, const uint8_t* data, std::size_t size, int64_t recv);
  void publishStatus(const std::string& state);
  void summary() const;

  RecorderOptions opts_;
  bus::MessageBus& bus_;
  LogWriter writer_;
  std::map<std::string, ChannelStats> stats_;  ///< the first kMaxChannels channels
  ChannelStats other_;                         ///< the others together
  bus::SeqTracker gaps_;  ///< keyed by channel (HEARTBEAT: by channel and process), kMaxSequences at most
  app::LogThrottle gap_log_;  ///< every gap is counted; the first 5 per key are logged, then 1 in 1000
  bool sequences_full_ = false;
  int64_t received_ = 0;
  int64_t status_seq_ = 0;
  int64_t awaited_status_seq_ = -1;  ///< our final status, once published: recorded when it comes back
  bool final_status_back_ = false, status_recorded_ = false;
  app::Heartbeat hb_;
  std::chrono::steady_clock::time_point next_status_;
};

}  // namespace lcmloc::logger
