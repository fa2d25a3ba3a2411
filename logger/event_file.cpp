#include "lcmloc/logger/event_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace lcmloc::logger {
namespace {
void put32(uint8_t* p, uint32_t v) {
  for (int i = 3; i >= 0; --i, v >>= 8) p[i] = static_cast<uint8_t>(v & 0xff);
}
void put64(uint8_t* p, uint64_t v) {
  for (int i = 7; i >= 0; --i, v >>= 8) p[i] = static_cast<uint8_t>(v & 0xff);
}
}  // namespace

void encodeEventHeader(uint8_t* out, int64_t eventnum, int64_t utime, uint32_t channel_len, uint32_t data_len) {
  put32(out, 0xEDA1DA01u);
  put64(out + 4, static_cast<uint64_t>(eventnum));
  put64(out + 12, static_cast<uint64_t>(utime));
  put32(out + 20, channel_len);
  put32(out + 24, data_len);
}

EventFile::EventFile(const std::string& path, std::size_t buffer_bytes, bool background)
    : path_(path), buffer_bytes_(buffer_bytes), background_(background) {
  const auto parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error("cannot open log file '" + path + "' for writing: " + std::strerror(errno));
  buf_.reserve(buffer_bytes_ + 65536);
  if (background_) {
    wbuf_.reserve(buffer_bytes_ + 65536);
    writer_ = std::thread([this] { writerLoop(); });
  }
}

EventFile::~EventFile() { close(); }

void EventFile::writerLoop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [this] { return busy_ || quit_; });
    if (!busy_) return;
    lock.unlock();
    std::size_t whole = 0, count = 0;
    const int err = writeBuffer(wbuf_, wends_, whole, count);
    lock.lock();
    werr_ = err;
    wwhole_ = whole;
    wcount_ = count;
    busy_ = false;
    cv_.notify_all();
  }
}

int EventFile::finishBackground() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return !busy_; });
  file_bytes_ += static_cast<int64_t>(wwhole_);
  events_written_ += static_cast<int64_t>(wcount_);
  wwhole_ = wcount_ = 0;
  inflight_ = 0;
  const int err = werr_;
  werr_ = 0;
  if (err != 0) {  // what was buffered after the failed write goes with it
    buf_.clear();
    ends_.clear();
    events_ = events_written_;
  }
  return err;
}

int EventFile::append(int64_t utime, const std::string& channel, const void* data, std::size_t size) {
  if (fd_ < 0) return EBADF;
  const std::size_t start = buf_.size();
  buf_.resize(start + 28 + channel.size() + size);
  encodeEventHeader(buf_.data() + start, events_, utime, static_cast<uint32_t>(channel.size()),
                    static_cast<uint32_t>(size));
  std::memcpy(buf_.data() + start + 28, channel.data(), channel.size());
  if (size) std::memcpy(buf_.data() + start + 28 + channel.size(), data, size);
  ends_.push_back(buf_.size());
  ++events_;
  if (buf_.size() >= buffer_bytes_) return writeOut();
  return 0;
}

int EventFile::writeOut() {
  if (background_) {
    if (const int err = finishBackground()) return err;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      buf_.swap(wbuf_);
      ends_.swap(wends_);
      inflight_ = static_cast<int64_t>(wbuf_.size());
      busy_ = true;
    }
    cv_.notify_all();
    buf_.clear();
    ends_.clear();
    return 0;
  }
  return writeNow();
}

int EventFile::writeNow() {
  std::size_t whole = 0, count = 0;
  const int err = writeBuffer(buf_, ends_, whole, count);
  file_bytes_ += static_cast<int64_t>(whole);
  events_written_ += static_cast<int64_t>(count);
  if (err != 0) events_ = events_written_;
  buf_.clear();
  ends_.clear();
  return err;
}

int EventFile::writeBuffer(const std::vector<uint8_t>& buf, const std::vector<std::size_t>& ends, std::size_t& whole,
                           std::size_t& count) {
  std::size_t done = 0;
  int err = 0;
  while (done < buf.size()) {
    const ssize_t n = ::write(fd_, buf.data() + done, buf.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      err = errno;
      break;
    }
    if (n == 0) { err = EIO; break; }
    done += static_cast<std::size_t>(n);
  }
  if (err == 0) {
    whole = buf.size();
    count = ends.size();
    return 0;
  }
  // Keep only whole events: cut the file back to the last event that was written entirely.
  whole = count = 0;
  for (std::size_t e : ends) {
    if (e > done) break;
    whole = e;
    ++count;
  }
  // file_bytes_ is only changed by the caller's thread; here the file's end is read from the fd.
  const off_t start = ::lseek(fd_, 0, SEEK_CUR) - static_cast<off_t>(done);
  if (::ftruncate(fd_, start + static_cast<off_t>(whole)) != 0) { /* nothing more we can do; reported via err */ }
  ::lseek(fd_, start + static_cast<off_t>(whole), SEEK_SET);
  return err;
}

int EventFile::flush(bool sync) {
  if (fd_ < 0) return EBADF;
  if (background_)
    if (const int err = finishBackground()) return err;
  if (const int err = buf_.empty() ? 0 : writeNow()) return err;
  if (sync && ::fsync(fd_) != 0) return errno;
  return 0;
}

int EventFile::close(bool sync) {
  if (fd_ < 0) return 0;
  int err = flush(sync);
  if (writer_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      quit_ = true;
    }
    cv_.notify_all();
    writer_.join();
  }
  if (::close(fd_) != 0 && err == 0) err = errno;
  fd_ = -1;
  return err;
}

}  // namespace lcmloc::logger
