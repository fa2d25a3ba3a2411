#pragma once
// Reading an LCM log ahead of its consumer: eval::LogScanner runs on a thread of its own and
// hands the events over in blocks of a few thousand, so that reading the file (stdio, the
// kernel's page cache, the event framing and damage scan) overlaps with what the consumer does
// with each event (the replay: decoding and the fusion daemon). The consumer sees exactly the
// events, in exactly the order, and exactly the damage reports that a LogScanner reading on the
// consumer's own thread would give (threaded = false does just that), so the output of the
// replay does not depend on the choice.
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

namespace lcmloc::replay {

class ReadAhead {
 public:
  /// Opens path (throws std::runtime_error as LogScanner does). threaded = false: no thread,
  /// every call reads from the file directly.
  ReadAhead(const std::string& path, bool threaded);
  ~ReadAhead();  ///< stops the reader thread (if still running) and waits for it
  ReadAhead(const ReadAhead&) = delete;
  ReadAhead& operator=(const ReadAhead&) = delete;

  /// The next intact event (valid until the next call), nullptr at the end of the file. Damage
  /// found before it is appended to issues first, in file order. Rethrows what the reader
  /// thread threw.
  const lcm::LogEvent* next(std::vector<eval::LogIssue>& issues);

  int64_t fileSize() const { return file_size_; }
  int64_t eventsRead() const { return events_read_; }  ///< events returned by next()
  /// Bytes of the file read so far (by the reader: up to a few blocks ahead of next()).
  int64_t position() const { return position_; }
  /// Bytes skipped over damage up to what next() has returned (the whole file once it returned
  /// nullptr).
  int64_t bytesUnreadable() const { return bytes_unreadable_; }
  bool damaged() const { return bytes_unreadable_ > 0; }

 private:
  struct Record {
    int64_t eventnum, timestamp;
    uint32_t channel_offset, channel_size, data_offset, data_size;
    uint32_t issues_end;  ///< issues of the block to report before this event
  };
  struct Block {
    std::vector<uint8_t> bytes;  ///< channel names and payloads of the records
    std::vector<Record> records;
    std::vector<eval::LogIssue> issues;
    bool end = false;            ///< the last block: the file is read
    int64_t position = 0, bytes_unreadable = 0;  ///< the scanner's, after the block's last event
  };
  void readerLoop();
  bool fill(Block& b);  ///< false at the end of the file
  void report(std::vector<eval::LogIssue>& issues, uint32_t upto);

  eval::LogScanner scanner_;
  std::vector<eval::LogIssue> scanner_issues_;  ///< the reader's (LogScanner's) own list
  int64_t file_size_ = 0, events_read_ = 0, position_ = 0, bytes_unreadable_ = 0;
  bool threaded_ = false;

  // Consumer side.
  std::unique_ptr<Block> current_;
  std::size_t next_record_ = 0;
  uint32_t issues_reported_ = 0;
  lcm::LogEvent event_;

  // Hand-over between the threads: full blocks in file order, empty blocks for reuse.
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::unique_ptr<Block>> full_, free_;
  int blocks_ = 0;  ///< blocks in existence (bounded)
  bool stop_ = false;
  std::exception_ptr error_;
  std::thread reader_;
};

}  // namespace lcmloc::replay
