#pragma once
// Big-endian integers as LCM writes them, in its messages (lcm_coretypes.h: integers, and
// doubles as their bit pattern) and in its log files (each event's header): loads and stores of
// one place for the encoders, the log writer and the readers that peek into a message without
// decoding it.
#include <cstdint>
#include <cstring>

namespace lcmloc::wire {

/// The n (1..8) bytes at p as one big-endian unsigned integer.
inline uint64_t loadBig(const uint8_t* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

inline uint64_t loadBig64(const uint8_t* p) {
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  uint64_t v;
  std::memcpy(&v, p, sizeof v);
  return __builtin_bswap64(v);
#else
  return loadBig(p, 8);
#endif
}

/// Stores v at p, most significant byte first (a byte swap and one store on a little-endian
/// machine).
inline void storeBig32(uint8_t* p, uint32_t v) {
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  v = __builtin_bswap32(v);
  std::memcpy(p, &v, sizeof v);
#else
  for (int i = 3; i >= 0; --i, v >>= 8) p[i] = static_cast<uint8_t>(v & 0xff);
#endif
}

inline void storeBig64(uint8_t* p, uint64_t v) {
#if __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  v = __builtin_bswap64(v);
  std::memcpy(p, &v, sizeof v);
#else
  for (int i = 7; i >= 0; --i, v >>= 8) p[i] = static_cast<uint8_t>(v & 0xff);
#endif
}

}  // namespace lcmloc::wire
