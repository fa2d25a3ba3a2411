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

EventFile::EventFile(const std::string& path, std::size_t buffer_bytes)
    : path_(path), buffer_bytes_(buffer_bytes) {
  const auto parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error("cannot open log file '" + path + "' for writing: " + std::strerror(errno));
  buf_.reserve(buffer_bytes_ + 65536);
}

EventFile::~EventFile() { close(); }

int EventFile::append(int64_t utime, const std::string& channel, const void* data, std::size_t size) {
  if (fd_ < 0) return EBADF;
  uint8_t header[28];
  encodeEventHeader(header, events_, utime, static_cast<uint32_t>(channel.size()), static_cast<uint32_t>(size));
  // (insert, not resize and copy: no zero fill of bytes about to be overwritten)
  buf_.insert(buf_.end(), header, header + sizeof header);
  const auto* ch = reinterpret_cast<const uint8_t*>(channel.data());
  buf_.insert(buf_.end(), ch, ch + channel.size());
  const auto* d = static_cast<const uint8_t*>(data);
  if (size) buf_.insert(buf_.end(), d, d + size);
  ends_.push_back(buf_.size());
  ++events_;
  if (buf_.size() >= buffer_bytes_) return writeOut();
  return 0;
}

int EventFile::writeOut() {
  std::size_t done = 0;
  int err = 0;
  while (done < buf_.size()) {
    const ssize_t n = ::write(fd_, buf_.data() + done, buf_.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      err = errno;
      break;
    }
    if (n == 0) { err = EIO; break; }
    done += static_cast<std::size_t>(n);
  }
  if (err == 0) {
    file_bytes_ += static_cast<int64_t>(buf_.size());
    events_written_ += static_cast<int64_t>(ends_.size());
  } else {
    // Keep only whole events: cut the file back to the last event that was written entirely.
    std::size_t whole = 0, count = 0;
    for (std::size_t e : ends_) {
      if (e > done) break;
      whole = e;
      ++count;
    }
    file_bytes_ += static_cast<int64_t>(whole);
    events_written_ += static_cast<int64_t>(count);
    if (::ftruncate(fd_, file_bytes_) != 0) { /* nothing more we can do; reported via err */ }
    ::lseek(fd_, file_bytes_, SEEK_SET);
    events_ = events_written_;
  }
  buf_.clear();
  ends_.clear();
  return err;
}

int EventFile::flush(bool sync) {
  if (fd_ < 0) return EBADF;
  if (const int err = buf_.empty() ? 0 : writeOut()) return err;
  if (sync && ::fsync(fd_) != 0) return errno;
  return 0;
}

int EventFile::close(bool sync) {
  if (fd_ < 0) return 0;
  int err = flush(sync);
  if (::close(fd_) != 0 && err == 0) err = errno;
  fd_ = -1;
  return err;
}

}  // namespace lcmloc::logger
