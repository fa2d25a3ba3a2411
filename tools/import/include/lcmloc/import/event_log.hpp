#pragma once
// Messages collected by an importer, written as an LCM log in time order through the logger's
// writer (logger::EventFile). Shared by lcmloc-import, lcmloc-import-vp and lcmloc-magnet-grid.
#include <cstdint>
#include <string>
#include <vector>

namespace lcmloc::import {

class EventLog {
 public:
  /// Adds one encoded message. At equal utime, events sort by order, then by insertion.
  template <typename T>
  void add(int64_t utime, int order, const std::string& channel, const T& msg) {
    std::vector<uint8_t> b(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(b.data(), 0, static_cast<int>(b.size()));
    events_.push_back({utime, order, static_cast<int64_t>(events_.size()), channel, std::move(b)});
    sorted_ = false;
  }
  /// Moves every message on channel (of type T, whose `utime` field is its time) by dt [us], in
  /// the message and as the event's time (a sensor's clock offset found by a fit).
  template <typename T>
  void retime(const std::string& channel, int64_t dt) {
    for (auto& e : events_) {
      if (e.channel != channel) continue;
      T m;
      if (m.decode(e.bytes.data(), 0, static_cast<int>(e.bytes.size())) < 0) continue;
      m.utime += dt;
      e.bytes.resize(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(e.bytes.data(), 0, static_cast<int>(e.bytes.size()));
      e.utime += dt;
      sorted_ = false;
    }
  }
  /// Sorts by (utime, order, insertion).
  void sort();
  std::size_t size() const { return events_.size(); }
  bool empty() const { return events_.empty(); }
  /// Time span of the events (after sort()); 0 when empty.
  int64_t firstUtime() const;
  int64_t lastUtime() const;
  /// Sorts and writes every event to path (event timestamp = message utime). Throws
  /// std::runtime_error when the file cannot be created or written.
  void write(const std::string& path);

 private:
  struct Event {
    int64_t utime;
    int order;
    int64_t index;
    std::string channel;
    std::vector<uint8_t> bytes;
  };
  std::vector<Event> events_;
  bool sorted_ = true;
};

}  // namespace lcmloc::import
