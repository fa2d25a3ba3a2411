#pragma once
// Short strings from messages (channel and filter names): equality without a library call (the
// per-message paths of the daemon and the replay compare a channel name several times per
// message, and the names are a few bytes long), and their form for a terminal or a log line.
#include <cstdint>
#include <cstring>
#include <string>

namespace lcmloc::core {

inline bool sameText(const std::string& a, const std::string& b) {
  const std::size_t n = a.size();
  if (n != b.size()) return false;
  const char* p = a.data();
  const char* q = b.data();
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    uint64_t x, y;
    std::memcpy(&x, p + i, 8);
    std::memcpy(&y, q + i, 8);
    if (x != y) return false;
  }
  for (; i < n; ++i)
    if (p[i] != q[i]) return false;
  return true;
}

/// text with every control character (bytes below 0x20 and 0x7f) replaced by '?': a string from
/// the bus or a log may hold any bytes, and printed as it is an escape sequence would move the
/// cursor, clear the screen or set the terminal's title, and a newline would fake a line of output.
inline std::string printable(std::string text) {
  for (auto& c : text)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return text;
}

}  // namespace lcmloc::core
