#include "lcmloc/eval/read_ahead.hpp"

#include <cstring>

namespace lcmloc::eval {
namespace {

/// A block is handed over once it holds this many bytes of channels and payloads (or
/// kBlockEvents events): about a thousand sensor messages, so the hand-over (a lock and a
/// wake-up) is paid once per thousand, and a block stays within the second-level cache.
constexpr std::size_t kBlockBytes = std::size_t{1} << 17;
constexpr std::size_t kBlockEvents = 4096;
/// Blocks in flight: the reading thread is at most this far ahead.
constexpr int kBlocks = 4;

}  // namespace

ReadAheadScanner::ReadAheadScanner(const std::string& path, std::vector<LogIssue>* issues)
    : scanner_(std::make_unique<LogScanner>(path, &scanner_issues_)), issues_(issues) {
  file_size_ = scanner_->fileSize();
  for (int i = 0; i < kBlocks; ++i) {
    auto b = std::make_unique<Block>();
    b->events.reserve(kBlockEvents);
    b->bytes.reserve(kBlockBytes + 4096);
    free_.push_back(std::move(b));
  }
  thread_ = std::thread([this] { run(); });
}

ReadAheadScanner::~ReadAheadScanner() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool ReadAheadScanner::fill(Block& b) {
  LogScanner& s = *scanner_;
  std::size_t issues_seen = scanner_issues_.size();
  auto takeIssues = [&] {
    for (; issues_seen < scanner_issues_.size(); ++issues_seen)
      b.issues.emplace_back(b.events.size(), std::move(scanner_issues_[issues_seen]));
  };
  while (b.events.size() < kBlockEvents && b.bytes.size() < kBlockBytes) {
    const lcm::LogEvent* ev = s.next();
    takeIssues();  // (damage is recorded as the event after it is found, or at the end)
    if (!ev) {
      b.last = true;
      break;
    }
    const std::size_t at = b.bytes.size();
    const auto channel_len = static_cast<uint32_t>(ev->channel.size());
    const auto data_len = static_cast<uint32_t>(ev->datalen);
    b.bytes.resize(at + channel_len + data_len);
    std::memcpy(b.bytes.data() + at, ev->channel.data(), channel_len);
    if (data_len > 0) std::memcpy(b.bytes.data() + at + channel_len, ev->data, data_len);
    b.events.push_back({ev->eventnum, ev->timestamp, s.eventOffset(), s.position(), s.bytesUnreadable(),
                        channel_len, data_len, at});
  }
  scanner_issues_.clear();
  b.end_position = s.position();
  b.end_unreadable = s.bytesUnreadable();
  return !b.last;
}

void ReadAheadScanner::run() {
  try {
    readBlocks();
  } catch (...) {  // (LogScanner throws only when memory runs out): the caller rethrows it
    {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
    }
    cv_.notify_all();
  }
}

void ReadAheadScanner::readBlocks() {
  while (true) {
    std::unique_ptr<Block> b;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return stop_ || !free_.empty(); });
      if (stop_) return;
      b = std::move(free_.front());
      free_.pop_front();
    }
    b->clear();
    const bool more = fill(*b);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      full_.push_back(std::move(b));
    }
    cv_.notify_all();
    if (!more) return;
  }
}

void ReadAheadScanner::nextBlock() {
  std::unique_lock<std::mutex> lock(mutex_);
  if (current_) free_.push_back(std::move(current_));
  cv_.notify_all();
  // (the thread ends after its last block, or with an error)
  cv_.wait(lock, [this] { return !full_.empty() || error_; });
  if (full_.empty()) std::rethrow_exception(error_);
  current_ = std::move(full_.front());
  full_.pop_front();
  index_ = issue_ = 0;
}

const lcm::LogEvent* ReadAheadScanner::next() {
  while (!at_end_) {
    if (current_) {
      Block& b = *current_;
      // Damage before the next event (or, past the last one, at the end of the file).
      for (; issue_ < b.issues.size() && b.issues[issue_].first <= index_; ++issue_)
        if (issues_) issues_->push_back(b.issues[issue_].second);
      if (index_ < b.events.size()) {
        const Event& e = b.events[index_++];
        const auto* p = b.bytes.data() + e.bytes;
        if (event_.channel.size() != e.channel_len || std::memcmp(event_.channel.data(), p, e.channel_len) != 0)
          event_.channel.assign(reinterpret_cast<const char*>(p), e.channel_len);
        event_.eventnum = e.eventnum;
        event_.timestamp = e.timestamp;
        event_.datalen = static_cast<int32_t>(e.data_len);
        event_.data = const_cast<uint8_t*>(p + e.channel_len);
        event_offset_ = e.offset;
        position_ = e.end;
        bytes_unreadable_ = e.bytes_unreadable;
        ++events_read_;
        return &event_;
      }
      if (b.last) {
        position_ = b.end_position;
        bytes_unreadable_ = b.end_unreadable;
        at_end_ = true;
        break;
      }
    }
    nextBlock();
  }
  return nullptr;
}

}  // namespace lcmloc::eval
