#pragma once
// A log throttle for problems that can repeat once per message.
#include <cstdint>
#include <map>
#include <string>

namespace lcmloc::app {

/// Log throttle for problems that can repeat per message (gaps, rejected inputs): allow() is true
/// for the first 5 occurrences of each key, then for one in a thousand (the counts themselves
/// are kept elsewhere and reported whole).
class LogThrottle {
 public:
  bool allow(const std::string& key) {
    const int64_t n = ++counts_[key];
    return n <= 5 || n % 1000 == 0;
  }
 private:
  std::map<std::string, int64_t> counts_;
};

}  // namespace lcmloc::app
