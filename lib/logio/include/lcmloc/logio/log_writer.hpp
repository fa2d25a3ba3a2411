#pragma once
// The logger's writing half: the receive side only enqueues into a bounded queue (drops are
// counted per channel, never silent); a writer thread appends whole events to standard LCM log
// files (EventFile), starting a new file by size, by time or on request (SIGHUP), writing each
// batch to the kernel at once and fsync()ing every flush period. A failed write (disk full,
// file size limit) stops the writer: the file keeps every whole event written before, later
// messages are counted as lost/dropped and failed() tells the main loop to exit non-zero.
// A new file that cannot be opened (its directory gone or unwritable) is no such failure: the
// writer goes on recording into the file it has, reports it (error log, WriterStats::
// rotate_failures / rotate_error) and tries again at the next request, or, for size and time,
// kRotateRetry later.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <ctime>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "lcmloc/logio/event_file.hpp"

namespace lcmloc::logger {

/// At most this many channels get statistics of their own (the logger's per-channel counts, the
/// writer's drops by channel); the others are counted together under kOtherChannels. A bus with
/// thousands of channel names (a bug, or hostile traffic) must not grow the logger's memory and
/// its LOGGER_STATUS without bound. Every message is recorded all the same.
inline constexpr std::size_t kMaxChannels = 1000;
inline const std::string kOtherChannels = "(other channels)";

/// A size or time rotation that could not open its new file is tried again this much later (a
/// requested one, SIGHUP, at the next request).
inline constexpr double kRotateRetry = 1.0;  // [s]

struct Event {
  std::string channel;
  std::vector<uint8_t> data;
  int64_t recv_utime = 0;
};

struct WriterOptions {
  std::string pattern = "out/run.lcmlog";  ///< strftime codes and {index} (see fileName)
  std::size_t capacity = 100000;           ///< queued messages
  int64_t queue_bytes = 512ll << 20;       ///< queued payload bytes
  int64_t max_file_bytes = 0;              ///< 0 = no size rotation
  double max_file_seconds = 0;             ///< 0 = no time rotation
  double flush_period = 0.2;               ///< fsync period [s]
  bool overwrite = false;                  ///< replace an existing file instead of picking a free name
};

struct WriterStats {
  int64_t written = 0;         ///< events handed to the kernel, all files
  int64_t dropped = 0;         ///< refused by push (queue full, or after a write error)
  int64_t write_lost = 0;      ///< accepted but lost in a failed write
  int64_t bytes_written = 0;   ///< all files
  int64_t flushed_events = 0;  ///< events in the files at the last fsync
  int32_t files = 0;           ///< files opened
  int32_t queue_depth = 0;
  std::string file;            ///< current file
  bool failed = false;
  std::string error;           ///< what failed (when failed)
  int64_t rotate_failures = 0; ///< attempts to start a new file that could not open it
  std::string rotate_error;    ///< why the last attempt failed; "" once a new file was opened
};

/// Name of file number index (0-based) from pattern at time t (local time): strftime codes are
/// expanded and "{index}" becomes the index with 3 digits. A name that is already taken (by an
/// earlier run, or an earlier file of this one) gets "-NNN" before its extension, the first
/// free one from -001 (or from -index without "{index}"). overwrite lets a name of an earlier
/// run be taken again, never one of this run's own files (own: the names written so far).
std::string fileName(const std::string& pattern, int index, std::time_t t, bool overwrite = false,
                     const std::vector<std::string>& own = {});

class LogWriter {
 public:
  /// Opens the first file; throws std::runtime_error when it cannot.
  explicit LogWriter(WriterOptions opts);
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  /// Enqueues; returns false (and counts a drop) when the queue is full or the writer failed.
  bool push(Event ev);
  /// Asks the writer thread to start a new file after what is queued now.
  void requestRotate();
  /// Writes what is queued, fsyncs and closes the file; idempotent.
  void close();

  WriterStats stats() const;
  bool failed() const;
  /// Messages refused by push, per channel (at most kMaxChannels of them; the rest under
  /// kOtherChannels).
  std::map<std::string, int64_t> droppedByChannel() const;
  /// Paths of every file opened so far, in order.
  std::vector<std::string> files() const;

 private:
  void run();
  /// Opens the next file (writer thread, and constructor); on failure returns null and sets *error.
  std::unique_ptr<EventFile> openNext(std::string* error);
  /// Starts a new file; when it cannot be opened, keeps the current one and reports it.
  void rotate(bool requested);
  void fail(int err, const std::string& what);
  void finishFile();

  WriterOptions opts_;
  std::unique_ptr<EventFile> file_;
  std::chrono::steady_clock::time_point file_opened_;
  std::chrono::steady_clock::time_point rotate_retry_at_{};  // a size/time rotation failed: not before
  int64_t failed_in_a_row_ = 0;                               // rotations that failed since the last new file
  int64_t closed_bytes_ = 0, closed_events_ = 0;  // of files already closed (writer thread)
  int64_t appended_ = 0;                           // events given to EventFile (writer thread)

  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Event> queue_;
  int64_t queued_bytes_ = 0;
  bool closing_ = false, rotate_requested_ = false;
  std::size_t rotate_at_ = 0;  // queue position of the requested new file
  WriterStats stats_;
  std::vector<std::string> paths_;
  std::map<std::string, int64_t> dropped_by_channel_;
  std::thread thread_;
};

}  // namespace lcmloc::logger
