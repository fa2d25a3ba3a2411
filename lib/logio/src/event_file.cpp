#include "lcmloc/logio/event_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "lcmloc/wire.hpp"

namespace lcmloc::logger {

void encodeEventHeader(uint8_t* out, int64_t eventnum, int64_t utime, uint32_t channel_len, uint32_t data_len) {
  wire::storeBig32(out, 0xEDA1DA01u);
  wire::storeBig64(out + 4, static_cast<uint64_t>(eventnum));
  wire::storeBig64(out + 12, static_cast<uint64_t>(utime));
  wire::storeBig32(out + 20, channel_len);
  wire::storeBig32(out + 24, data_len);
}

EventFile::EventFile(const std::string& path, std::size_t buffer_bytes)
    : path_(path), buffer_bytes_(buffer_bytes) {
  const auto parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  // A file truncated on open is written out to disk when it is closed (ext4's auto_da_alloc: a
  // forced flush of the whole file, tens of ms for tens of MB), a new one when the kernel sees fit:
  // an existing regular file with no other name is replaced by a new one. A symlink, a file with
  // other hard links, or one whose directory forbids the unlink is truncated in place, as before.
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_nlink == 1) ::unlink(path.c_str());
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error("cannot open log file '" + path + "' for writing: " + std::strerror(errno));
  buf_.resize(buffer_bytes_ + 65536);  // (the storage; used_ of it hold events)
}

EventFile::~EventFile() { close(); }

int EventFile::append(int64_t utime, const std::string& channel, const void* data, std::size_t size) {
  if (fd_ < 0) return EBADF;
  const std::size_t n = 28 + channel.size() + size;
  if (used_ + n > buf_.size()) buf_.resize(std::max(2 * buf_.size(), used_ + n));  // (an event beyond the buffer)
  uint8_t* p = buf_.data() + used_;
  encodeEventHeader(p, events_, utime, static_cast<uint32_t>(channel.size()), static_cast<uint32_t>(size));
  std::memcpy(p + 28, channel.data(), channel.size());
  if (size) std::memcpy(p + 28 + channel.size(), data, size);
  used_ += n;
  ends_.push_back(used_);
  ++events_;
  if (used_ < buffer_bytes_) return 0;
  return writeOut();
}

int EventFile::dropBuffered(int err) {
  used_ = 0;
  ends_.clear();
  events_ = events_written_;
  return err;
}

int EventFile::writeOut() {
  if (const int err = writeEvents(buf_.data(), used_, ends_)) return dropBuffered(err);
  used_ = 0;
  ends_.clear();
  return 0;
}

int EventFile::writeEvents(const uint8_t* data, std::size_t used, const std::vector<std::size_t>& ends) {
  std::size_t done = 0;
  int err = 0;
  while (done < used) {
    const ssize_t n = ::write(fd_, data + done, used - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      err = errno;
      break;
    }
    if (n == 0) { err = EIO; break; }
    done += static_cast<std::size_t>(n);
  }
  if (err == 0) {
    file_bytes_ += static_cast<int64_t>(used);
    events_written_ += static_cast<int64_t>(ends.size());
  } else {
    // Keep only whole events: cut the file back to the last event that was written entirely.
    std::size_t whole = 0, count = 0;
    for (std::size_t e : ends) {
      if (e > done) break;
      whole = e;
      ++count;
    }
    file_bytes_ += static_cast<int64_t>(whole);
    events_written_ += static_cast<int64_t>(count);
    if (::ftruncate(fd_, file_bytes_) != 0) { /* nothing more we can do; reported via err */ }
    ::lseek(fd_, file_bytes_, SEEK_SET);
  }
  return err;
}

int EventFile::flush(bool sync) {
  if (fd_ < 0) return EBADF;
  if (const int err = used_ == 0 ? 0 : writeOut()) return err;
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
