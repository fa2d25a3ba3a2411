#include "lcmloc/core/channel_name.hpp"

#include <mutex>
#include <unordered_set>

namespace lcmloc::core {

const std::string& ChannelName::intern(std::string_view name) {
  // Node-based: a name, once in, stays where it is. Never destroyed (names are few, and a
  // ChannelName may outlive any static destructor).
  static auto* names = new std::unordered_set<std::string>();
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  return *names->emplace(name).first;
}

}  // namespace lcmloc::core
