#include "lcmloc/replay/log_bus.hpp"

#include <cstring>
#include <stdexcept>

#include "lcmloc/logio/event_file.hpp"
#include "lcmloc/wire.hpp"

namespace lcmloc::replay {

/// The output log: the standard LCM log format (events numbered 0, 1, ... as lcm::LogFile numbers
/// them), written through a 256 kB user-space buffer (one write(2) per 256 kB, not several stdio
/// calls per event) by the thread that publishes (the replay's applying thread). Not on a thread
/// of its own: with the replay's two, a third takes turns with them on the two CPUs of the
/// machines this runs on, each of its writes stopping the reading or the applying side as long
/// (on the bench's hour, the aim's ratio had medians of 0.43 and 0.40 with a writing thread, 0.51
/// and 0.44 without, in two rounds of alternating runs). Not a larger buffer: each page of it
/// is a page fault when first touched, microseconds on a virtual machine, while 256 kB makes a
/// write(2) of a few hundred microseconds, many times what the call itself costs.
class LogWriter {
 public:
  explicit LogWriter(const std::string& path) {
    try {
      file = std::make_unique<logger::EventFile>(path, std::size_t{1} << 18);
    } catch (const std::exception& e) {
      throw std::runtime_error("cannot create output log '" + path + "': " + e.what());
    }
  }
  std::unique_ptr<logger::EventFile> file;
};

int64_t messageUtime(const void* data, std::size_t size, int64_t fallback) {
  if (size < 16) return fallback;
  return static_cast<int64_t>(wire::loadBig64(static_cast<const uint8_t*>(data) + 8));
}

LogBus::LogBus(const std::string& output) {
  if (!output.empty()) writer_ = std::make_unique<LogWriter>(output);
}

LogBus::~LogBus() = default;

void LogBus::close() {
  if (writer_ && write_error_.empty())
    if (const int err = writer_->file->close(false); err != 0) writeFailed(err);
  writer_.reset();
}

bool LogBus::writeFailed(int err) {
  write_error_ = std::strerror(err);
  return false;
}

std::map<std::string, int64_t> LogBus::writtenPerChannel() const {
  std::map<std::string, int64_t> m;
  for (const auto& [ch, n] : per_channel_) m[ch] += n;
  return m;
}

bool LogBus::write(const std::string& channel, const void* data, std::size_t size, int64_t timestamp) {
  if (!write_error_.empty()) return false;
  if (writer_)
    if (const int err = writer_->file->append(timestamp, channel, data, size); err != 0) return writeFailed(err);
  ++written_;
  // A handful of channels: a linear search beats a map lookup per event.
  auto it = per_channel_.begin();
  while (it != per_channel_.end() && it->first != channel) ++it;
  if (it == per_channel_.end())
    per_channel_.emplace_back(channel, 1);
  else
    ++it->second;
  return true;
}

bool LogBus::publishRaw(const std::string& channel, const void* data, std::size_t size) {
  return write(channel, data, size, messageUtime(data, size, 0));
}

bool LogBus::copy(const std::string& channel, const void* data, std::size_t size, int64_t fallback_utime) {
  return write(channel, data, size, messageUtime(data, size, fallback_utime));
}

void LogBus::subscribeRaw(const std::string& channel, RawHandler handler) {
  // LCM channel regexes are POSIX extended and match the whole channel name.
  subs_.push_back({std::regex("^(" + channel + ")$", std::regex::extended), std::move(handler)});
  route_.clear();
  last_channel_ = nullptr;
  last_route_ = nullptr;
}

const std::vector<std::size_t>& LogBus::route(const std::string& channel) {
  auto it = route_.find(channel);
  if (it == route_.end()) {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < subs_.size(); ++i)
      if (std::regex_match(channel, subs_[i].re)) idx.push_back(i);
    it = route_.emplace(channel, std::move(idx)).first;
  }
  last_channel_ = &it->first;  // map nodes are stable until route_.clear()
  last_route_ = &it->second;
  return it->second;
}

int LogBus::dispatch(const std::string& channel, const void* data, std::size_t size, int64_t recv_utime) {
  // (the usual case, the channel of the event before, inline: no call per event)
  const auto& idx = last_channel_ && *last_channel_ == channel ? *last_route_ : route(channel);
  return call(idx, channel, data, size, recv_utime);
}

int LogBus::dispatchAgain(const std::string& channel, const void* data, std::size_t size, int64_t recv_utime) {
  if (!last_route_) return dispatch(channel, data, size, recv_utime);  // (no dispatch before it)
  return call(*last_route_, channel, data, size, recv_utime);
}

int LogBus::call(const std::vector<std::size_t>& idx, const std::string& channel, const void* data, std::size_t size,
                 int64_t recv_utime) {
  for (std::size_t i : idx) subs_[i].handler(channel, static_cast<const uint8_t*>(data), size, recv_utime);
  return static_cast<int>(idx.size());
}

}  // namespace lcmloc::replay
