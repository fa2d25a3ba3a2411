#include "lcmloc/bus/transport.hpp"

#include <poll.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <regex>
#include <unordered_map>

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

/// The own receive (ownReceive()): subscriptions as LCM 1.3.1 matches them (the channel regex
/// anchored at both ends), and which of them each channel name goes to, found once per name.
struct Bus::Own {
  struct Route {
    std::regex re;
    RawHandler handler;
  };
  std::unique_ptr<UdpmReceiver> socket;  ///< opened at the first subscription
  std::vector<Route> routes;
  std::unordered_map<std::string, std::vector<std::size_t>> by_channel;
  std::string key;                    ///< (reused for lookups)
  std::string channel;                ///< the channel being dispatched
  std::vector<std::size_t> dispatching;  ///< (reused: a handler may subscribe while it runs)
  static constexpr std::size_t kMaxNames = 4096;  ///< a sender inventing names cannot grow it further

  const std::vector<std::size_t>& routesFor(std::string_view channel) {
    key.assign(channel.data(), channel.size());
    auto it = by_channel.find(key);
    if (it != by_channel.end()) return it->second;
    if (by_channel.size() >= kMaxNames) by_channel.clear();
    std::vector<std::size_t> match;
    for (std::size_t i = 0; i < routes.size(); ++i)
      if (std::regex_match(key, routes[i].re)) match.push_back(i);
    return by_channel.emplace(key, std::move(match)).first->second;
  }
};

namespace {
constexpr const char* kSelfTestChannel = "LCM_SELF_TEST";  // the channel and text LCM's own self test uses
constexpr const char* kSelfTestText = "lcm self test";
std::string routeHint(const std::string& url) {
  return url.rfind("udpm://", 0) == 0 || url.empty()
             ? " (udpm needs a multicast route; on loopback: `ip route add 224.0.0.0/4 dev lo` as root)"
             : "";
}
}  // namespace

Bus::Bus(const std::string& url) : url_(url) {
  const char* receive = std::getenv("LCMLOC_LCM_RECEIVE");
  if (!(receive && std::strcmp(receive, "lcm") == 0)) own_ = parseUdpmUrl(url);
  lcm_ = std::make_unique<lcm::LCM>(url);
  // (getFileno() starts LCM's receive thread and runs its self test: only when LCM receives)
  if (!lcm_->good() || (!own_ && lcm_->getFileno() < 0))
    throw TransportError("cannot start LCM on '" + url + "'" + routeHint(url));
  if (own_) {
    rx_ = std::make_unique<Own>();
    selfTest();
  }
}

void Bus::selfTest() {
  // As LCM's own: a message to ourselves through the group, sent again every 100 ms, must come
  // back (a multicast route and no firewall in the way). The socket is closed again; the first
  // subscription opens it, so a process that only publishes holds no receive buffer.
  try {
    UdpmReceiver socket(*own_);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    bool back = false;
    while (!back && std::chrono::steady_clock::now() < until) {
      if (lcm_->publish(kSelfTestChannel, kSelfTestText, static_cast<unsigned>(std::strlen(kSelfTestText))) < 0)
        break;
      const auto resend = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
      while (!back && std::chrono::steady_clock::now() < resend) {
        if (socket.handle(10, [](std::string_view ch) { return ch == kSelfTestChannel; },
                          [&](const UdpmMessage& m) {
                            back = m.size == std::strlen(kSelfTestText) &&
                                   std::memcmp(m.data, kSelfTestText, m.size) == 0;
                          }) < 0)
          break;
      }
    }
    if (!back) throw TransportError("LCM's self test message did not come back");
  } catch (const TransportError& e) {
    throw TransportError("cannot start LCM on '" + url_ + "': " + e.what() + routeHint(url_));
  }
}

bool Bus::wanted(std::string_view channel) { return !rx_->routesFor(channel).empty(); }

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
  if (own_) {
    std::regex re;
    try {
      re = std::regex("^" + channel + "$", std::regex::ECMAScript | std::regex::optimize);
    } catch (const std::regex_error& e) {
      throw TransportError("cannot subscribe to '" + channel + "': not a valid channel regex (" + e.what() + ")");
    }
    if (!rx_->socket) rx_->socket = std::make_unique<UdpmReceiver>(*own_);
    rx_->routes.push_back(Own::Route{std::move(re), std::move(handler)});
    rx_->by_channel.clear();
    return;
  }
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

int Bus::handle(int timeout_ms) {
  if (!own_) return lcm_->handleTimeout(timeout_ms);
  if (!rx_->socket) {  // nothing subscribed: nothing to receive
    const int r = ::poll(nullptr, 0, timeout_ms);
    return r < 0 ? -1 : 0;
  }
  Own& o = *rx_;
  return o.socket->handle(
      timeout_ms, [this](std::string_view ch) { return wanted(ch); },
      [&o](const UdpmMessage& m) {
        o.dispatching = o.routesFor(m.channel);
        o.channel.assign(o.key);  // (routesFor left the name there; assign keeps its storage)
        for (std::size_t i : o.dispatching) o.routes[i].handler(o.channel, m.data, m.size, m.recv_utime);
      });
}

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
