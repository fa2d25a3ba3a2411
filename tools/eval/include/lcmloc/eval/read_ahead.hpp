#pragma once
// LogScanner on a thread of its own: the file is read and its events framed (sync word, header,
// channel, payload; damage skipped and recorded) ahead of the caller, who takes the events in
// file order from blocks handed over whole. The offline replay reads through it so that reading
// the log overlaps with the fusion that consumes it, on a second core.
//
// The caller sees exactly what a LogScanner of the same file gives: the same events in the same
// order, the same counters, and each damaged stretch appended to `issues` when the event it
// precedes is taken (at the end of the file for damage at the end), as LogScanner appends it.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/eval/log_reader.hpp"

namespace lcmloc::eval {

class ReadAheadScanner {
 public:
  /// Opens the file at once (throws std::runtime_error as LogScanner does) and starts reading.
  /// issues may be null.
  ReadAheadScanner(const std::string& path, std::vector<LogIssue>* issues);
  /// Stops the reading thread (also when events are left).
  ~ReadAheadScanner();
  ReadAheadScanner(const ReadAheadScanner&) = delete;
  ReadAheadScanner& operator=(const ReadAheadScanner&) = delete;

  /// The next intact event (valid until the next call), or nullptr at the end of the file.
  /// Rethrows what stopped the reading thread (std::bad_alloc), after the events before it.
  const lcm::LogEvent* next();
  int64_t eventOffset() const { return event_offset_; }   ///< byte offset of the last event returned
  int64_t position() const { return position_; }          ///< bytes consumed up to it
  int64_t fileSize() const { return file_size_; }
  int64_t eventsRead() const { return events_read_; }     ///< intact events returned
  int64_t bytesUnreadable() const { return bytes_unreadable_; }
  bool damaged() const { return bytes_unreadable_ > 0; }

 private:
  /// Events framed by the reading thread: their headers, and channel + payload bytes back to back.
  struct Event {
    int64_t eventnum, timestamp, offset, end;  ///< end: the scanner's position after the event
    int64_t bytes_unreadable;                  ///< the scanner's count when it returned the event
    uint32_t channel_len, data_len;
    std::size_t bytes;                         ///< where its channel starts in Block::bytes
  };
  struct Block {
    std::vector<Event> events;
    std::vector<uint8_t> bytes;
    /// Damage met before events[i] (i = events.size(): after the last, at the end of the file).
    std::vector<std::pair<std::size_t, LogIssue>> issues;
    bool last = false;  ///< the end of the file comes after it
    int64_t end_position = 0, end_unreadable = 0;
    void clear() {
      events.clear();
      bytes.clear();
      issues.clear();
      last = false;
    }
  };
  void run();
  void readBlocks();
  bool fill(Block& b);  ///< false at the end of the file
  void nextBlock();     ///< the next full block into current_ (waits for it)

  std::unique_ptr<LogScanner> scanner_;  ///< used by the reading thread only, once started
  std::vector<LogIssue> scanner_issues_;
  std::vector<LogIssue>* issues_;

  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::unique_ptr<Block>> full_, free_;
  bool stop_ = false;
  std::exception_ptr error_;  ///< what ended the reading thread early
  std::thread thread_;

  std::unique_ptr<Block> current_;
  std::size_t index_ = 0;  ///< next event of current_
  std::size_t issue_ = 0;  ///< next issue of current_
  bool at_end_ = false;
  lcm::LogEvent event_{};
  int64_t file_size_ = 0, events_read_ = 0, bytes_unreadable_ = 0, position_ = 0, event_offset_ = 0;
};

}  // namespace lcmloc::eval
