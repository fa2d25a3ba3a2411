#pragma once
// The logger's two halves: the receive side only enqueues into a bounded queue (drops are
// counted per channel), a writer thread appends to a standard LCM log file.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

namespace lcmloc::logger {

struct Event {
  std::string channel;
  std::vector<uint8_t> data;
  int64_t recv_utime = 0;
};

class LogWriter {
 public:
  /// Opens path for writing (creating parent directories); throws std::runtime_error.
  LogWriter(const std::string& path, std::size_t capacity);
  ~LogWriter();
  /// Enqueues; returns false (and counts a drop) when the queue is full.
  bool push(Event ev);
  /// Writes what is queued, flushes and closes the file; idempotent.
  void close();

  int64_t written() const;
  int64_t writeErrors() const;
  int64_t dropped() const;
  std::map<std::string, int64_t> droppedByChannel() const;

 private:
  void run();

  std::unique_ptr<lcm::LogFile> log_;
  std::size_t capacity_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Event> queue_;
  bool closing_ = false;
  int64_t written_ = 0, write_errors_ = 0, dropped_ = 0;
  std::map<std::string, int64_t> dropped_by_channel_;
  std::thread thread_;
};

/// The seq of an lcmloc message read generically: every lcmloc type starts (after the 8-byte
/// fingerprint) with int64 utime then int64 seq, so seq is bytes 16..23, big-endian.
bool readSeq(const uint8_t* data, std::size_t size, int64_t* seq);

}  // namespace lcmloc::logger
