#include "lcmloc/replay/read_ahead.hpp"

#include <algorithm>
#include <cstring>

namespace lcmloc::replay {
namespace {
// A block holds up to this many events or bytes (whichever comes first); at most kMaxBlocks exist
// (one being filled, the others waiting or being consumed): memory stays bounded at a few MB
// whatever the log's size.
constexpr std::size_t kBlockEvents = 4096;
constexpr std::size_t kBlockBytes = std::size_t{1} << 20;
constexpr int kMaxBlocks = 4;
}  // namespace

ReadAhead::ReadAhead(const std::string& path, bool threaded)
    : scanner_(path, &scanner_issues_), file_size_(scanner_.fileSize()), threaded_(threaded) {
  if (threaded_) reader_ = std::thread([this] { readerLoop(); });
}

ReadAhead::~ReadAhead() {
  if (!reader_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  reader_.join();
}

bool ReadAhead::fill(Block& b) {
  b.bytes.clear();
  b.records.clear();
  b.issues.clear();
  b.end = false;
  while (b.records.size() < kBlockEvents && b.bytes.size() < kBlockBytes) {
    const lcm::LogEvent* ev = scanner_.next();
    // Damage found on the way to this event is reported before it.
    for (auto& is : scanner_issues_) b.issues.push_back(std::move(is));
    scanner_issues_.clear();
    if (!ev) {
      b.end = true;
      break;
    }
    Record r{};
    r.eventnum = ev->eventnum;
    r.timestamp = ev->timestamp;
    r.channel_offset = static_cast<uint32_t>(b.bytes.size());
    r.channel_size = static_cast<uint32_t>(ev->channel.size());
    b.bytes.insert(b.bytes.end(), ev->channel.begin(), ev->channel.end());
    r.data_offset = static_cast<uint32_t>(b.bytes.size());
    r.data_size = static_cast<uint32_t>(ev->datalen);
    const auto* data = static_cast<const uint8_t*>(ev->data);
    b.bytes.insert(b.bytes.end(), data, data + ev->datalen);
    r.issues_end = static_cast<uint32_t>(b.issues.size());
    b.records.push_back(r);
  }
  b.position = scanner_.position();
  b.bytes_unreadable = scanner_.bytesUnreadable();
  return !b.end;
}

void ReadAhead::readerLoop() {
  try {
    while (true) {
      std::unique_ptr<Block> b;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        changed_.wait(lock, [this] { return stop_ || !free_.empty() || blocks_ < kMaxBlocks; });
        if (stop_) return;
        if (!free_.empty()) {
          b = std::move(free_.front());
          free_.pop_front();
        } else {
          ++blocks_;
        }
      }
      if (!b) b = std::make_unique<Block>();
      const bool more = fill(*b);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        full_.push_back(std::move(b));
      }
      changed_.notify_all();
      if (!more) return;
    }
  } catch (...) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
    }
    changed_.notify_all();
  }
}

void ReadAhead::report(std::vector<eval::LogIssue>& issues, uint32_t upto) {
  for (; issues_reported_ < upto; ++issues_reported_) issues.push_back(current_->issues[issues_reported_]);
}

const lcm::LogEvent* ReadAhead::next(std::vector<eval::LogIssue>& issues) {
  if (!threaded_) {
    const lcm::LogEvent* ev = scanner_.next();
    for (auto& is : scanner_issues_) issues.push_back(std::move(is));
    scanner_issues_.clear();
    position_ = scanner_.position();
    bytes_unreadable_ = scanner_.bytesUnreadable();
    if (ev) ++events_read_;
    return ev;
  }
  while (!current_ || next_record_ == current_->records.size()) {
    if (current_) {
      report(issues, static_cast<uint32_t>(current_->issues.size()));
      bytes_unreadable_ = current_->bytes_unreadable;
      if (current_->end) return nullptr;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        free_.push_back(std::move(current_));
      }
      changed_.notify_all();
    }
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return !full_.empty() || error_; });
    if (full_.empty()) std::rethrow_exception(error_);
    current_ = std::move(full_.front());
    full_.pop_front();
    next_record_ = 0;
    issues_reported_ = 0;
    position_ = current_->position;
  }
  const Record& r = current_->records[next_record_++];
  report(issues, r.issues_end);
  const uint8_t* base = current_->bytes.data();
  event_.eventnum = r.eventnum;
  event_.timestamp = r.timestamp;
  event_.channel.assign(reinterpret_cast<const char*>(base + r.channel_offset), r.channel_size);
  event_.datalen = static_cast<int32_t>(r.data_size);
  event_.data = const_cast<uint8_t*>(base + r.data_offset);
  ++events_read_;
  return &event_;
}

}  // namespace lcmloc::replay
