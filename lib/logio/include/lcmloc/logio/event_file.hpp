#pragma once
// Writes the standard LCM log format directly with POSIX calls (what lcm-logplayer and
// lcm::LogFile read): per event a 28-byte big-endian header (sync 0xEDA1DA01, int64 event
// number, int64 utime, uint32 channel length, uint32 data length), the channel, the payload.
//
// Events are appended to a user-space buffer and written out whole. When a write fails
// (ENOSPC, EFBIG under RLIMIT_FSIZE, EIO) the file is truncated back to the end of the last
// complete event, so what was written before stays a readable log.
#include <cstdint>
#include <string>
#include <vector>

namespace lcmloc::logger {

class EventFile {
 public:
  /// Creates path, making parent directories; throws std::runtime_error. An existing regular
  /// file there with no other hard link is replaced by a new file (unlinked, then created); a
  /// symlink, a file with other links, or one that cannot be unlinked is truncated in place.
  explicit EventFile(const std::string& path, std::size_t buffer_bytes = 1 << 20);
  ~EventFile();
  EventFile(const EventFile&) = delete;
  EventFile& operator=(const EventFile&) = delete;

  /// Appends one event (numbered 0, 1, ... in this file). Returns 0, or the errno of a failed
  /// write (the event and anything buffered with it are then not in the file).
  int append(int64_t utime, const std::string& channel, const void* data, std::size_t size);
  /// Writes the buffer to the kernel; with sync also fsync()s. Returns 0 or an errno.
  int flush(bool sync);
  /// Flushes, fsyncs (unless sync is false) and closes; returns 0 or an errno. Idempotent.
  int close(bool sync = true);

  const std::string& path() const { return path_; }
  /// Bytes in the file plus bytes buffered.
  int64_t size() const { return file_bytes_ + static_cast<int64_t>(used_); }
  /// Events appended (buffered ones included) / events written to the kernel.
  int64_t events() const { return events_; }
  int64_t eventsWritten() const { return events_written_; }
  /// Bytes in the file (whole events only).
  int64_t fileBytes() const { return file_bytes_; }

 private:
  int writeOut();
  /// Writes `used` bytes of events ending at `ends` at the end of the file; on failure cuts the
  /// file back to its last whole event. Updates file_bytes_ and events_written_; returns an errno.
  int writeEvents(const uint8_t* data, std::size_t used, const std::vector<std::size_t>& ends);
  /// After a failed write: what is buffered is dropped, numbering goes on after the last event
  /// in the file.
  int dropBuffered(int err);

  std::string path_;
  int fd_ = -1;
  std::size_t buffer_bytes_;
  std::vector<uint8_t> buf_;       ///< storage: the first used_ bytes are buffered events
  std::size_t used_ = 0;
  std::vector<std::size_t> ends_;  ///< end of each buffered event within buf_
  int64_t file_bytes_ = 0, events_ = 0, events_written_ = 0;
};

/// The 28-byte header of one event (exposed for tests).
void encodeEventHeader(uint8_t* out, int64_t eventnum, int64_t utime, uint32_t channel_len, uint32_t data_len);

}  // namespace lcmloc::logger
