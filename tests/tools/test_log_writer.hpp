#pragma once
// Test helper: writes LCM log files event by event with lcm::LogFile and remembers where each
// event starts (byte offset) and its channel, so tests can damage a chosen event.
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

namespace lcmloc::testlog {

/// Where each event of a written log starts, and its channel.
struct LogLayout {
  std::vector<int64_t> starts;
  std::vector<std::string> channels;
};

/// Writes events with lcm::LogFile and remembers where each one starts.
class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : log_(path, "w") {}
  template <typename T>
  void add(const std::string& channel, const T& msg, int64_t utime) {
    std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent ev;
    ev.eventnum = 0;
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(buf.size());
    ev.data = buf.data();
    layout.starts.push_back(offset_);
    layout.channels.push_back(channel);
    offset_ += 28 + static_cast<int64_t>(channel.size()) + ev.datalen;
    ASSERT_EQ(log_.writeEvent(&ev), 0);
  }
  LogLayout layout;

 private:
  lcm::LogFile log_;
  int64_t offset_ = 0;
};

}  // namespace lcmloc::testlog
