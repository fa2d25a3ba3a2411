#pragma once
// The lcmloc message types known to the log tools and the logger: fingerprint -> type name,
// and a field visitor that turns a payload into named values (arrays expanded as name_0,
// name_1, ...; 2-D arrays as name_0_1) for CSV export.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace lcmloc::logger {

struct Field {
  std::string name;
  std::string value;  ///< numbers in full precision, strings as they are
  bool is_string = false;
};
using Fields = std::vector<Field>;

struct TypeInfo {
  int64_t hash = 0;
  std::string name;  ///< e.g. "lcmloc.odometry_t"
  /// Decodes a whole payload (fingerprint included) into fields; false when it does not decode.
  std::function<bool(const uint8_t*, std::size_t, Fields*)> fields;
};

/// Every lcmloc type (all start with int64 utime, int64 seq after the fingerprint).
const std::vector<TypeInfo>& knownTypes();
/// The type whose fingerprint starts the payload, or nullptr (unknown or shorter than 8 bytes).
const TypeInfo* findType(const uint8_t* data, std::size_t size);
/// The payload's first 8 bytes (big-endian fingerprint); false when shorter.
bool readFingerprint(const uint8_t* data, std::size_t size, int64_t* hash);

/// The seq of an lcmloc message read generically: bytes 16..23 after the fingerprint and utime.
/// Only meaningful when findType() knows the payload.
bool readSeq(const uint8_t* data, std::size_t size, int64_t* seq);

}  // namespace lcmloc::logger
