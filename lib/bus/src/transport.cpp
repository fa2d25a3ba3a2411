#include "lcmloc/bus/transport.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include <spdlog/spdlog.h>

namespace lcmloc::bus {

std::string defaultLcmUrl() {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  if (env && *env) return env;
  return "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
}

std::string withReceiveBuffer(const std::string& url, int bytes) {
  if (bytes <= 0 || url.rfind("udpm://", 0) != 0 || receiveBufferOf(url) > 0 ||
      url.find("recv_buf_size=") != std::string::npos)
    return url;
  const auto q = url.find('?');
  const char* sep = q == std::string::npos ? "?" : (q + 1 == url.size() || url.back() == '&' ? "" : "&");
  return url + sep + "recv_buf_size=" + std::to_string(bytes);
}

std::optional<std::string> urlOption(const std::string& url, const std::string& key) {
  const auto q = url.find('?');
  if (q == std::string::npos) return std::nullopt;
  for (std::size_t pos = q + 1; pos < url.size();) {
    std::size_t end = url.find('&', pos);
    if (end == std::string::npos) end = url.size();
    const std::string opt = url.substr(pos, end - pos);
    if (opt.rfind(key + "=", 0) == 0) return opt.substr(key.size() + 1);
    pos = end + 1;
  }
  return std::nullopt;
}

long long receiveBufferOf(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0) return 0;
  const auto v = urlOption(url, "recv_buf_size");
  return v ? std::atoll(v->c_str()) : 0;
}

long long kernelRmemMax(const std::string& path) {
  long long v = -1;
  if (std::FILE* f = std::fopen(path.c_str(), "r")) {
    if (std::fscanf(f, "%lld", &v) != 1) v = -1;
    std::fclose(f);
  }
  return v;
}

int64_t wallMicros() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

/// One LCM subscription: LCM 1.3.1 has no lambda subscribe, so a member function forwards.
struct Bus::Sub {
  RawHandler handler;
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    handler(channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size, rbuf->recv_utime);
  }
};

Bus::Bus(const std::string& url) : url_(url) {
  lcm_ = std::make_unique<lcm::LCM>(url);
  if (!lcm_->good() || lcm_->getFileno() < 0) {
    std::string hint;
    if (url.rfind("udpm://", 0) == 0 || url.empty())
      hint = " (udpm needs a multicast route; on loopback: `ip route add 224.0.0.0/4 dev lo` as root)";
    throw TransportError("cannot start LCM on '" + url + "'" + hint);
  }
}

Bus::~Bus() = default;

bool Bus::publishRaw(const std::string& channel, const void* data, std::size_t size) {
  if (lcm_->publish(channel, data, static_cast<unsigned int>(size)) < 0)
    return publishFailed(channel, "publish");
  return true;
}

bool MessageBus::publishFailed(const std::string& channel, const char* what) {
  ++publish_errors_;
  if (!publish_error_logged_[channel]) {
    publish_error_logged_[channel] = true;
    spdlog::error("{}: {} failed (message too large or transport down); further failures on this "
                  "channel are counted, not logged", channel, what);
  }
  return false;
}

void Bus::subscribeRaw(const std::string& channel, RawHandler handler) {
  // LCM 1.3.1's C++ subscribe returns a Subscription even when the channel regex does not
  // compile (its C subscription is then null, and the first use of it crashes): probe with the
  // C API, which returns null (and prints GLib's reason on stderr).
  lcm_t* c = lcm_->getUnderlyingLCM();
  lcm_subscription_t* probe =
      lcm_subscribe(c, channel.c_str(), [](const lcm_recv_buf_t*, const char*, void*) {}, nullptr);
  if (!probe) throw TransportError("cannot subscribe to '" + channel + "': not a valid channel regex");
  lcm_unsubscribe(c, probe);
  auto sub = std::make_unique<Sub>();
  sub->handler = std::move(handler);
  lcm::Subscription* s = lcm_->subscribe(channel, &Sub::onMessage, sub.get());
  if (!s) throw TransportError("cannot subscribe to '" + channel + "'");
  s->setQueueCapacity(0);  // unbounded: bursts must not be dropped silently
  subs_.push_back(std::move(sub));
}

int Bus::handle(int timeout_ms) { return lcm_->handleTimeout(timeout_ms); }

bool MessageBus::drain(int max_ms) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(max_ms);
  while (handle(0) > 0)
    if (std::chrono::steady_clock::now() >= until) return false;
  return true;
}

void MessageBus::decodeFailed(const std::string& channel, const std::string& why) {
  if (decode_errors_[channel]++ == 0)
    spdlog::warn("{}: {}; further decode errors on this channel are counted, not logged", channel, why);
}

int64_t MessageBus::decodeErrors() const {
  int64_t n = 0;
  for (const auto& kv : decode_errors_) n += kv.second;
  return n;
}

int64_t MessageBus::decodeErrors(const std::string& channel) const {
  auto it = decode_errors_.find(channel);
  return it == decode_errors_.end() ? 0 : it->second;
}

}  // namespace lcmloc::bus
