#pragma once
// A log file read event by event by its 28-byte headers (GUIDE: sync 0xEDA1DA01, int64 event
// number, int64 utime, uint32 channel length, uint32 data length, channel, payload): the whole
// events, and what is left after the last whole one (a torn event of a killed writer).
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

struct ScannedLog {
  struct Event {
    std::string channel;
    std::vector<uint8_t> data;
  };
  std::vector<Event> events;
  std::size_t size = 0;       ///< [bytes] of the file
  std::size_t whole = 0;      ///< [bytes] taken by whole events
  bool bad_sync = false;      ///< an event header without the sync word where one was due
};

inline ScannedLog scanLog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ScannedLog out;
  out.size = b.size();
  const auto u32 = [&](std::size_t at) {
    return (uint32_t{b[at]} << 24) | (uint32_t{b[at + 1]} << 16) | (uint32_t{b[at + 2]} << 8) | uint32_t{b[at + 3]};
  };
  std::size_t at = 0;
  while (at + 28 <= b.size()) {
    if (u32(at) != 0xEDA1DA01u) {
      out.bad_sync = true;
      break;
    }
    const std::size_t clen = u32(at + 20), dlen = u32(at + 24);
    if (at + 28 + clen + dlen > b.size()) break;  // torn
    ScannedLog::Event ev;
    ev.channel.assign(reinterpret_cast<const char*>(&b[at + 28]), clen);
    ev.data.assign(b.begin() + static_cast<std::ptrdiff_t>(at + 28 + clen),
                   b.begin() + static_cast<std::ptrdiff_t>(at + 28 + clen + dlen));
    out.events.push_back(std::move(ev));
    at += 28 + clen + dlen;
  }
  out.whole = at;
  return out;
}
