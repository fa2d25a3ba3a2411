#include "lcmloc/logio/log_reader.hpp"


#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>

#include <sys/stat.h>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/wire.hpp"

namespace lcmloc::logio {
namespace {

constexpr int64_t kEventHeaderBytes = 28;  // sync, event number, utime, channel len, data len

/// Size of the regular file at path. Throws std::runtime_error when there is none: a directory
/// or a device would otherwise read as one damaged stretch of st_size bytes.
int64_t logFileSize(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw std::runtime_error("cannot open log '" + path + "': no such file");
  if (!fs::is_regular_file(st))
    throw std::runtime_error("cannot read log '" + path + "': it " +
                             (fs::is_directory(st) ? "is a directory" : "is not a regular file"));
  return static_cast<int64_t>(fs::file_size(path));
}

/// fread without the stream lock: a LogScanner's FILE is only ever used by the thread that
/// reads with it, and as soon as the process has a second thread every locked fread costs two
/// atomic operations, three times per event.
std::size_t readBytes(void* out, std::size_t n, FILE* f) { return fread_unlocked(out, 1, n, f); }

/// Offset of the next sync word at or after from, or -1 when there is none.
int64_t findSync(FILE* f, int64_t from) {
  static const unsigned char kSync[4] = {0xED, 0xA1, 0xDA, 0x01};
  if (fseeko(f, from, SEEK_SET) != 0) return -1;
  std::vector<unsigned char> buf(1 << 16);
  int64_t base = from;
  size_t keep = 0;  // bytes carried over from the previous chunk
  while (true) {
    const size_t n = readBytes(buf.data() + keep, buf.size() - keep, f);
    if (n == 0) return -1;
    const size_t len = keep + n;
    for (size_t i = 0; i + 4 <= len; ++i)
      if (std::equal(kSync, kSync + 4, buf.begin() + static_cast<std::ptrdiff_t>(i)))
        return base + static_cast<int64_t>(i);
    keep = std::min<size_t>(3, len);
    std::copy(buf.begin() + static_cast<std::ptrdiff_t>(len - keep),
              buf.begin() + static_cast<std::ptrdiff_t>(len), buf.begin());
    base += static_cast<int64_t>(len - keep);
  }
}

}  // namespace

struct LogScanner::Impl {
  std::unique_ptr<FILE, int (*)(FILE*)> file{nullptr, &std::fclose};
  std::vector<char> iobuf = std::vector<char>(1 << 20);
  int64_t file_pos = 0;  ///< where the stream stands (seek only when it differs)
  std::vector<uint8_t> data;
  lcm::LogEvent event{};
};

LogScanner::LogScanner(const std::string& path, std::vector<LogIssue>* issues)
    : impl_(std::make_unique<Impl>()), issues_(issues) {
  file_size_ = logFileSize(path);
  impl_->file.reset(std::fopen(path.c_str(), "rb"));
  if (!impl_->file) throw std::runtime_error("cannot open log '" + path + "' for reading");
  std::setvbuf(impl_->file.get(), impl_->iobuf.data(), _IOFBF, impl_->iobuf.size());
  if (file_size_ == 0 && issues_)
    issues_->push_back({0, 0, "empty file (0 bytes): no LCM event; not a log, or one whose writer had not written "
                              "an event yet"});
}

int64_t LogScanner::currentFileSize() const {
  struct stat st {};
  return ::fstat(fileno(impl_->file.get()), &st) == 0 ? static_cast<int64_t>(st.st_size) : file_size_;
}

LogScanner::~LogScanner() = default;

void LogScanner::closeDamage(int64_t resume_at) {
  if (!dmg_open_) return;
  const int64_t skipped = resume_at - dmg_start_;
  bytes_unreadable_ += skipped;
  std::ostringstream s;
  if (resume_at >= file_size_ && dmg_start_ == 0 && events_read_ == 0)
    s << "no LCM event in the whole file (" << skipped << " bytes, no sync word 0xEDA1DA01 followed by a whole "
      << "event): not an LCM log, or damaged throughout";
  else if (resume_at >= file_size_)
    s << "log ends in a damaged or truncated event: the last " << skipped << " bytes from byte "
      << dmg_start_ << " could not be read (" << events_read_ << " events read before)";
  if (resume_at >= file_size_) {
    const int64_t now = currentFileSize();
    if (now > file_size_)
      s << "; the file has grown to " << now << " bytes since it was opened with " << file_size_
        << " (still being written?): what was added was not read";
  }
  else
    s << "damaged event at byte " << dmg_start_ << ": skipped " << skipped
      << " bytes, resumed at byte " << resume_at;
  if (issues_) issues_->push_back({dmg_event_index_, dmg_start_, s.str()});
  dmg_open_ = false;
}

/// Reads a whole intact event starting at pos into impl_->event; false when there is none.
bool LogScanner::readEventAt(int64_t pos) {
  FILE* f = impl_->file.get();
  if (impl_->file_pos != pos && fseeko(f, pos, SEEK_SET) != 0) return false;
  impl_->file_pos = -1;  // unknown until the event is read whole
  unsigned char h[kEventHeaderBytes];
  if (readBytes(h, sizeof h, f) != sizeof h || wire::loadBig(h, 4) != 0xEDA1DA01u) return false;
  const auto channel_len = static_cast<int64_t>(wire::loadBig(h + 20, 4));
  const auto data_len = static_cast<int64_t>(wire::loadBig(h + 24, 4));
  if (channel_len <= 0 || channel_len >= 1000 || data_len >= (int64_t{1} << 31) ||
      pos + kEventHeaderBytes + channel_len + data_len > file_size_)
    return false;
  lcm::LogEvent& ev = impl_->event;
  ev.channel.resize(static_cast<std::size_t>(channel_len));
  impl_->data.resize(static_cast<std::size_t>(data_len));
  if (readBytes(ev.channel.data(), ev.channel.size(), f) != ev.channel.size() ||
      (data_len > 0 && readBytes(impl_->data.data(), impl_->data.size(), f) != impl_->data.size()))
    return false;
  ev.eventnum = static_cast<int64_t>(wire::loadBig(h + 4, 8));
  ev.timestamp = static_cast<int64_t>(wire::loadBig(h + 12, 8));
  ev.datalen = static_cast<int32_t>(data_len);
  ev.data = impl_->data.data();
  impl_->file_pos = pos + kEventHeaderBytes + channel_len + data_len;
  return true;
}

const lcm::LogEvent* LogScanner::next() {
  while (pos_ < file_size_) {
    if (readEventAt(pos_)) {
      closeDamage(pos_);
      event_offset_ = pos_;
      pos_ = impl_->file_pos;
      ++events_read_;
      return &impl_->event;
    }
    if (!dmg_open_) {
      dmg_open_ = true;
      dmg_event_index_ = events_read_;
      dmg_start_ = pos_;
    }
    // Resynchronise; a sync word past the size at opening (a file still being written) is not read.
    const int64_t next = findSync(impl_->file.get(), pos_ + 1);
    impl_->file_pos = -1;
    if (next < 0 || next >= file_size_) {
      closeDamage(file_size_);
      pos_ = file_size_;
      return nullptr;
    }
    pos_ = next;
  }
  return nullptr;
}

ScanSummary scanLog(const std::string& path, const std::function<void(const RawEvent&)>& on_event,
                    const std::atomic<bool>* stop) {
  ScanSummary out;
  LogScanner scanner(path, &out.issues);
  out.file_size = scanner.fileSize();
  while (!(stop && stop->load())) {
    const lcm::LogEvent* ev = scanner.next();
    if (!ev) break;
    RawEvent raw;
    raw.index = scanner.eventsRead() - 1;
    raw.offset = scanner.eventOffset();
    raw.eventnum = ev->eventnum;
    raw.utime = ev->timestamp;
    raw.channel = &ev->channel;
    raw.data = static_cast<const uint8_t*>(ev->data);
    raw.size = ev->datalen;
    on_event(raw);
  }
  if (stop && stop->load()) out.interrupted = true;
  out.events_read = scanner.eventsRead();
  out.bytes_unreadable = scanner.bytesUnreadable();
  out.damaged = scanner.damaged();
  return out;
}

std::string badUtimeIssue(const std::string& channel, int64_t utime) {
  return channel + " message with utime " + std::to_string(utime) + " skipped: |utime| >= 2^62 us";
}

std::string LogIssue::describe() const {
  if (event_index < 0) return "whole log: " + what;
  return "event " + std::to_string(event_index) + " at byte " + std::to_string(byte_offset) + ": " + what;
}

void printIssues(std::ostream& os, const std::vector<LogIssue>& issues, std::size_t shown) {
  for (std::size_t k = 0; k < issues.size() && k < shown; ++k) os << "  " << issues[k].describe() << "\n";
  if (issues.size() > shown) os << "  ... and " << issues.size() - shown << " more (see report.json)\n";
}

void printBadUtime(std::ostream& os, int64_t skipped) {
  if (skipped > 0)
    os << "warning: " << skipped << " message(s) skipped for |utime| >= 2^62 us: not evaluated (see the issues)\n";
}

std::vector<std::string> uniqueStems(const std::vector<std::string>& names) {
  auto safe = [](std::string s) {
    if (s.size() > 200) s.resize(200);
    for (auto& c : s)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') c = '_';
    return s.empty() ? std::string("_") : s;
  };
  std::vector<std::string> stems(names.size());
  std::set<std::string> taken;
  for (std::size_t i = 0; i < names.size(); ++i)  // names that are stems already keep them
    if (safe(names[i]) == names[i] && taken.insert(names[i]).second) stems[i] = names[i];
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!stems[i].empty()) continue;
    const std::string base = safe(names[i]);
    std::string s = base;
    for (int k = 2; !taken.insert(s).second; ++k) s = base + "_" + std::to_string(k);
    stems[i] = s;
  }
  return stems;
}

}  // namespace lcmloc::logio
