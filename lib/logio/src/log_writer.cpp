#include "lcmloc/logio/log_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <spdlog/spdlog.h>

namespace lcmloc::logger {

std::string fileName(const std::string& pattern, int index, std::time_t t, bool overwrite,
                     const std::vector<std::string>& own) {
  char idx[16];
  std::snprintf(idx, sizeof idx, "%03d", index);
  std::string p = pattern;
  bool has_index = false;
  for (std::size_t pos; (pos = p.find("{index}")) != std::string::npos;) {
    p.replace(pos, 7, idx);
    has_index = true;
  }
  std::tm tm{};
  localtime_r(&t, &tm);
  std::vector<char> buf(p.size() * 4 + 256);
  const std::size_t n = std::strftime(buf.data(), buf.size(), p.c_str(), &tm);
  std::string name = (n == 0 && !p.empty()) ? p : std::string(buf.data(), n);
  auto usable = [&](const std::string& n) {
    return std::find(own.begin(), own.end(), n) == own.end() && (overwrite || !std::filesystem::exists(n));
  };
  if (usable(name)) return name;
  // Taken: insert -NNN before the extension (of the file name, not of a directory).
  const std::filesystem::path path(name);
  const std::string stem = (path.parent_path() / path.stem()).string();
  const std::string ext = path.extension().string();
  for (int i = has_index ? 1 : std::max(index, 1);; ++i) {
    std::snprintf(idx, sizeof idx, "-%03d", i);
    std::string candidate = stem + idx + ext;
    if (usable(candidate)) return candidate;
  }
}

LogWriter::LogWriter(WriterOptions opts) : opts_(std::move(opts)) {
  std::string error;
  file_ = openNext(&error);
  if (!file_) throw std::runtime_error(error);
  thread_ = std::thread([this] { run(); });
}

LogWriter::~LogWriter() { close(); }

bool LogWriter::push(Event ev) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    const auto bytes = static_cast<int64_t>(ev.data.size() + ev.channel.size());
    if (closing_ || stats_.failed || queue_.size() >= opts_.capacity ||
        queued_bytes_ + bytes > opts_.queue_bytes) {
      ++stats_.dropped;
      auto it = dropped_by_channel_.find(ev.channel);
      if (it == dropped_by_channel_.end())
        it = dropped_by_channel_.emplace(dropped_by_channel_.size() < kMaxChannels ? ev.channel : kOtherChannels, 0).first;
      ++it->second;
      return false;
    }
    queued_bytes_ += bytes;
    queue_.push_back(std::move(ev));
  }
  cv_.notify_one();
  return true;
}

void LogWriter::requestRotate() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    rotate_requested_ = true;
    rotate_at_ = queue_.size();  // after what is queued now
  }
  cv_.notify_one();
}

void LogWriter::fail(int err, const std::string& what) {
  std::string why = std::strerror(err);
  if (err == ENOSPC) why = "disk full (ENOSPC)";
  else if (err == EFBIG) why = "file size limit reached (EFBIG)";
  else if (err == EDQUOT) why = "disk quota exceeded (EDQUOT)";
  std::lock_guard<std::mutex> lock(mu_);
  stats_.failed = true;
  stats_.error = what + ": " + why;
}

void LogWriter::finishFile() {
  if (!file_) return;
  const int err = file_->close();
  closed_bytes_ += file_->fileBytes();
  closed_events_ += file_->eventsWritten();
  if (err) fail(err, "writing " + file_->path());
  file_.reset();
}

std::unique_ptr<EventFile> LogWriter::openNext(std::string* error) {
  std::vector<std::string> own;
  {
    std::lock_guard<std::mutex> lock(mu_);
    own = paths_;
  }
  const int index = static_cast<int>(own.size());
  const std::time_t now = std::time(nullptr);
  const std::string name = fileName(opts_.pattern, index, now, opts_.overwrite, own);
  std::unique_ptr<EventFile> file;
  try {
    file = std::make_unique<EventFile>(name);
  } catch (const std::exception& e) {
    *error = e.what();
    return nullptr;
  }
  // (a name this run wrote already, from a pattern without {index}, is no earlier recording)
  if (const std::string wanted = fileName(opts_.pattern, index, now, true);
      wanted != name && std::find(own.begin(), own.end(), wanted) == own.end())
    spdlog::warn("{} exists (an earlier recording): writing {} instead (--overwrite replaces it)", wanted, name);
  file_opened_ = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(mu_);
  paths_.push_back(name);
  stats_.files = static_cast<int32_t>(paths_.size());
  stats_.file = name;
  return file;
}

void LogWriter::rotate(bool requested) {
  std::string error;
  auto next = openNext(&error);
  if (!next) {
    ++failed_in_a_row_;
    rotate_retry_at_ = std::chrono::steady_clock::now() +
                       std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(kRotateRetry));
    std::string current;
    {
      std::lock_guard<std::mutex> lock(mu_);
      ++stats_.rotate_failures;
      stats_.rotate_error = error;
      current = stats_.file;
    }
    // (a request is the operator's: each one is answered; the automatic retries of size and time
    // rotation, one per kRotateRetry, are logged the first 5 times, then 1 in 1000)
    if (requested || failed_in_a_row_ <= 5 || failed_in_a_row_ % 1000 == 0)
      spdlog::error("cannot start a new log file: {}; still recording into {} (attempt {}; tried again {})", error,
                    current, failed_in_a_row_,
                    requested ? "at the next SIGHUP, or by size/time rotation"
                              : fmt::format("in {} s, or at SIGHUP", kRotateRetry));
    return;
  }
  finishFile();
  file_ = std::move(next);
  std::string name;
  {
    std::lock_guard<std::mutex> lock(mu_);
    stats_.rotate_error.clear();
    name = stats_.file;
  }
  if (failed_in_a_row_ > 0)
    spdlog::info("new log file {} (after {} failed attempt(s) to start one)", name, failed_in_a_row_);
  else
    spdlog::info("new log file {}", name);
  failed_in_a_row_ = 0;
}

void LogWriter::run() {
  using clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(opts_.flush_period));
  const auto max_age = std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(opts_.max_file_seconds));
  auto next_flush = clock::now() + period;
  int64_t flushed = 0;
  std::deque<Event> batch;
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    cv_.wait_until(lock, next_flush, [this] { return closing_ || rotate_requested_ || !queue_.empty(); });
    batch.swap(queue_);
    queued_bytes_ = 0;
    const bool closing = closing_;
    const std::size_t rotate_at = rotate_requested_ ? rotate_at_ : SIZE_MAX;  // index in batch
    rotate_requested_ = false;
    bool failed = stats_.failed;
    lock.unlock();

    int64_t lost = 0;
    auto rotateNow = [&](bool requested) {
      rotate(requested);
      lock.lock();
      failed = stats_.failed;
      lock.unlock();
      failed = failed || !file_;
    };
    for (std::size_t k = 0; k < batch.size(); ++k) {
      auto& ev = batch[k];
      if (k == rotate_at && !failed && file_) rotateNow(true);
      if (failed || !file_) { ++lost; continue; }
      const int64_t size = 28 + static_cast<int64_t>(ev.channel.size() + ev.data.size());
      if (file_->events() > 0 &&
          ((opts_.max_file_bytes > 0 && file_->size() + size > opts_.max_file_bytes) ||
           (opts_.max_file_seconds > 0 && clock::now() - file_opened_ >= max_age)) &&
          clock::now() >= rotate_retry_at_) {
        rotateNow(false);
        if (failed) { ++lost; continue; }
      }
      ++appended_;
      if (const int err = file_->append(ev.recv_utime, ev.channel, ev.data.data(), ev.data.size())) {
        fail(err, "writing " + file_->path());
        failed = true;
      }
    }
    if (rotate_at != SIZE_MAX && rotate_at >= batch.size() && !failed && file_) rotateNow(true);
    batch.clear();
    if (!failed && file_) {
      const bool sync = clock::now() >= next_flush || closing;
      if (file_) {
        if (const int err = file_->flush(sync)) fail(err, "writing " + file_->path());
        else if (sync) flushed = closed_events_ + file_->eventsWritten();
      }
      if (sync) next_flush = clock::now() + period;
    }

    lock.lock();
    const int64_t written = closed_events_ + (file_ ? file_->eventsWritten() : 0);
    stats_.written = written;
    stats_.bytes_written = closed_bytes_ + (file_ ? file_->fileBytes() : 0);
    stats_.write_lost = (appended_ - written) + lost;
    stats_.flushed_events = flushed;
    if (closing && queue_.empty()) break;
  }
  lock.unlock();
  finishFile();  // fsync + close
  lock.lock();
  stats_.written = closed_events_;
  stats_.bytes_written = closed_bytes_;
  if (!stats_.failed) stats_.flushed_events = closed_events_;
}

void LogWriter::close() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (closing_) return;
    closing_ = true;
  }
  cv_.notify_one();
  if (thread_.joinable()) thread_.join();
}

WriterStats LogWriter::stats() const {
  std::lock_guard<std::mutex> l(mu_);
  WriterStats s = stats_;
  s.queue_depth = static_cast<int32_t>(queue_.size());
  return s;
}
bool LogWriter::failed() const { std::lock_guard<std::mutex> l(mu_); return stats_.failed; }
std::map<std::string, int64_t> LogWriter::droppedByChannel() const {
  std::lock_guard<std::mutex> l(mu_);
  return dropped_by_channel_;
}
std::vector<std::string> LogWriter::files() const {
  std::lock_guard<std::mutex> l(mu_);
  return paths_;
}

}  // namespace lcmloc::logger
