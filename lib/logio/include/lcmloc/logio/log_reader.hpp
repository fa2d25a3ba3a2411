#pragma once
// Reads an LCM log file directly (no network), event by event. A damaged log (truncated tail, corrupt event, undecodable payload) is read
// up to and past the damage where possible; every problem is recorded with its event index and
// byte offset.
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <map>
#include <ostream>
#include <string>
#include <vector>


namespace lcm {
struct LogEvent;
}  // namespace lcm

namespace lcmloc::logio {

/// Messages with |utime| >= kUtimeLimit (2^62 us, about 146,000 years) are skipped by the
/// readers, counted and reported as issues: the difference of any two utimes below it, and such
/// a utime plus or minus a tolerance, fits in int64.
constexpr int64_t kUtimeLimit = int64_t{1} << 62;
inline bool usableUtime(int64_t utime) { return utime > -kUtimeLimit && utime < kUtimeLimit; }
/// The issue recorded for a message of channel skipped for its utime.
std::string badUtimeIssue(const std::string& channel, int64_t utime);

/// to - from for from <= to, exact for any two int64 (the difference always fits in uint64).
inline uint64_t utimeSpan(int64_t from, int64_t to) { return static_cast<uint64_t>(to) - static_cast<uint64_t>(from); }

/// (utime - t0) in seconds without integer overflow, for any two utimes.
inline double secondsSince(int64_t utime, int64_t t0) {
  return utime >= t0 ? static_cast<double>(utimeSpan(t0, utime)) * 1e-6
                     : -(static_cast<double>(utimeSpan(utime, t0)) * 1e-6);
}

/// A problem found while reading: damage of the file or a message that could not be used.
struct LogIssue {
  int64_t event_index = 0;   ///< index of the event (0-based, counting events read so far); -1: the log as a whole
  int64_t byte_offset = 0;   ///< where in the file (-1 with event_index -1)
  std::string what;
  /// "event N at byte B: what", or "whole log: what".
  std::string describe() const;
};

/// The first `shown` issues, one indented line each, then how many more (in report.json).
void printIssues(std::ostream& os, const std::vector<LogIssue>& issues, std::size_t shown = 10);
/// A warning line when skipped (messages dropped for their utime, see kUtimeLimit) is not 0.
void printBadUtime(std::ostream& os, int64_t skipped);

/// One file-name stem per name, all different: letters, digits, '_' and '-' are kept, any other
/// byte becomes '_'. A name that is already such a stem keeps it; a stem taken by an earlier
/// name or by a name that is kept as it is gets "_2", "_3", ... (POSE_A.B next to POSE_A_B
/// gives POSE_A_B_2). At most 200 bytes before any suffix (file names end at 255).
std::vector<std::string> uniqueStems(const std::vector<std::string>& names);

/// Streams the intact events of any LCM log (ours, lcm-logger's) one at a time, in file order,
/// without the network. The format is parsed here rather than with lcm::LogFile: LCM 1.3.1's
/// reader also rejects an intact event when the sync word after it is damaged, and cannot say
/// where an event starts. Damage (a truncated tail, a corrupt event) is skipped by
/// resynchronising on the next sync word; each damaged stretch is appended to issues with the
/// index of the event it precedes and its byte offset. The file is read up to its size when it was
/// opened: a file that grows while it is read (a logger still writing) is read to that size, a
/// partial last event there is reported as a truncated tail (saying that the file has grown), and
/// what was added after the opening is not read. An empty file is reported as damaged. scanLog, readTrajectoryLog and the offline
/// replay (lcmloc-replay) all read through it.
class LogScanner {
 public:
  /// Throws std::runtime_error when the file cannot be opened or is not a regular file (a
  /// directory, a device: no log). issues may be null.
  LogScanner(const std::string& path, std::vector<LogIssue>* issues);
  ~LogScanner();
  LogScanner(const LogScanner&) = delete;
  LogScanner& operator=(const LogScanner&) = delete;
  /// The next intact event (valid until the next call), or nullptr at the end of the file.
  const lcm::LogEvent* next();
  int64_t eventOffset() const { return event_offset_; }   ///< byte offset of the last event returned
  int64_t position() const { return pos_; }               ///< bytes consumed so far
  int64_t fileSize() const { return file_size_; }
  int64_t eventsRead() const { return events_read_; }     ///< intact events returned
  int64_t bytesUnreadable() const { return bytes_unreadable_; }
  /// Damaged: bytes that could not be read, or an empty file (no event at all; recorded as an issue).
  bool damaged() const { return bytes_unreadable_ > 0 || file_size_ == 0; }

 private:
  bool readEventAt(int64_t pos);
  int64_t currentFileSize() const;  ///< the file's size now (it may grow while it is read)
  void closeDamage(int64_t resume_at);
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<LogIssue>* issues_;
  int64_t file_size_ = 0, events_read_ = 0, bytes_unreadable_ = 0, pos_ = 0, event_offset_ = 0;
  bool dmg_open_ = false;
  int64_t dmg_event_index_ = 0, dmg_start_ = 0;
};

/// One intact event, as scanLog hands it out (data valid during the callback only).
struct RawEvent {
  int64_t index = 0;       ///< 0-based among intact events
  int64_t offset = 0;      ///< byte offset of its header
  int64_t eventnum = 0;    ///< event number stored in the file
  int64_t utime = 0;       ///< log timestamp (receive time) [us]
  const std::string* channel = nullptr;
  const uint8_t* data = nullptr;
  int32_t size = 0;
};

/// Decodes e into m; true when the whole payload is exactly one T.
template <typename T>
bool decodeEvent(const RawEvent& e, T& m) {
  return m.decode(e.data, 0, e.size) == e.size;
}

/// What scanLog found about the file itself.
struct ScanSummary {
  int64_t file_size = 0;
  int64_t events_read = 0;
  int64_t bytes_unreadable = 0;
  bool damaged = false;
  bool interrupted = false;
  std::vector<LogIssue> issues;  ///< damaged stretches: where (event index, byte) and how long
};

/// Reads every intact event of any LCM log (ours, lcm-logger's) in file order, resynchronising
/// past damage on the next sync word; each damaged stretch is recorded with its position.
/// Throws std::runtime_error when the file cannot be opened. stop is polled between events.
ScanSummary scanLog(const std::string& path, const std::function<void(const RawEvent&)>& on_event,
                    const std::atomic<bool>* stop = nullptr);

}  // namespace lcmloc::logio
