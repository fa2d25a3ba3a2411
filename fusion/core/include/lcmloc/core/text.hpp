#pragma once
// Equality of short strings (channel and filter names) without a library call: the per-message
// paths of the daemon and the replay compare a channel name several times per message, and the
// names are a few bytes long.
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

}  // namespace lcmloc::core
