#include "lcmloc/bus/memory_bus.hpp"

namespace lcmloc::bus {

bool MemoryBus::publishRaw(const std::string& channel, const void* data, std::size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  Message m{channel, std::vector<uint8_t>(p, p + size), recv_utime_};
  published_.push_back(m);
  queue_.push_back(std::move(m));
  return true;
}

void MemoryBus::subscribeRaw(const std::string& channel, RawHandler handler) {
  auto sub = std::make_unique<Sub>();
  try {
    // As LCM: a POSIX extended regex, surrounded by ^ and $ (not grouped), searched for.
    sub->re = std::regex("^" + channel + "$", std::regex::extended | std::regex::nosubs);
  } catch (const std::regex_error& e) {
    throw TransportError("cannot subscribe to '" + channel + "': not a valid channel regex (" + e.what() + ")");
  }
  sub->handler = std::move(handler);
  subs_.push_back(std::move(sub));
}

int MemoryBus::subscribers(const std::string& channel) const {
  int n = 0;
  for (const auto& s : subs_) n += std::regex_search(channel, s->re) ? 1 : 0;
  return n;
}

int MemoryBus::handle(int) {
  if (queue_.empty()) return 0;
  const Message m = std::move(queue_.front());
  queue_.pop_front();
  // (a handler may subscribe: the subscriptions made before this message was handed out get it)
  const std::size_t n = subs_.size();
  for (std::size_t i = 0; i < n; ++i)
    if (std::regex_search(m.channel, subs_[i]->re))
      subs_[i]->handler(m.channel, m.data.data(), m.data.size(), m.recv_utime);
  return 1;
}

std::size_t MemoryBus::deliverAll(std::size_t max_messages) {
  std::size_t n = 0;
  while (handle(0) > 0)
    if (++n >= max_messages && !queue_.empty())
      throw std::runtime_error("MemoryBus: still messages queued after delivering " + std::to_string(n));
  return n;
}

void MemoryBus::inject(const std::string& channel, std::vector<uint8_t> bytes) {
  queue_.push_back(Message{channel, std::move(bytes), recv_utime_});
}

std::vector<MemoryBus::Message> MemoryBus::published(const std::string& channel) const {
  std::vector<Message> out;
  for (const auto& m : published_)
    if (m.channel == channel) out.push_back(m);
  return out;
}

}  // namespace lcmloc::bus
