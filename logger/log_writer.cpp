#include "log_writer.hpp"

#include <filesystem>
#include <stdexcept>

#include <spdlog/spdlog.h>

namespace lcmloc::logger {

LogWriter::LogWriter(const std::string& path, std::size_t capacity) : capacity_(capacity) {
  const auto parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  log_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!log_->good()) throw std::runtime_error("cannot open log file '" + path + "' for writing");
  thread_ = std::thread([this] { run(); });
}

LogWriter::~LogWriter() { close(); }

bool LogWriter::push(Event ev) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (closing_ || queue_.size() >= capacity_) {
      ++dropped_;
      ++dropped_by_channel_[ev.channel];
      return false;
    }
    queue_.push_back(std::move(ev));
  }
  cv_.notify_one();
  return true;
}

void LogWriter::run() {
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    cv_.wait(lock, [this] { return closing_ || !queue_.empty(); });
    if (queue_.empty() && closing_) break;
    std::deque<Event> batch;
    batch.swap(queue_);
    lock.unlock();
    int64_t ok = 0, bad = 0;
    for (auto& ev : batch) {
      lcm::LogEvent le;
      le.eventnum = 0;  // assigned by LCM
      le.timestamp = ev.recv_utime;
      le.channel = ev.channel;
      le.datalen = static_cast<int32_t>(ev.data.size());
      le.data = ev.data.data();
      (log_->writeEvent(&le) == 0 ? ok : bad)++;
    }
    std::fflush(log_->getFilePtr());
    lock.lock();
    written_ += ok;
    write_errors_ += bad;
  }
}

void LogWriter::close() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (closing_) return;
    closing_ = true;
  }
  cv_.notify_one();
  if (thread_.joinable()) thread_.join();
  log_.reset();  // closes the file
}

int64_t LogWriter::written() const { std::lock_guard<std::mutex> l(mu_); return written_; }
int64_t LogWriter::writeErrors() const { std::lock_guard<std::mutex> l(mu_); return write_errors_; }
int64_t LogWriter::dropped() const { std::lock_guard<std::mutex> l(mu_); return dropped_; }
std::map<std::string, int64_t> LogWriter::droppedByChannel() const {
  std::lock_guard<std::mutex> l(mu_);
  return dropped_by_channel_;
}

bool readSeq(const uint8_t* data, std::size_t size, int64_t* seq) {
  if (size < 24) return false;
  uint64_t v = 0;
  for (int i = 16; i < 24; ++i) v = (v << 8) | data[i];
  *seq = static_cast<int64_t>(v);
  return true;
}

}  // namespace lcmloc::logger
