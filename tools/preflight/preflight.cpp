// lcmloc-preflight's checks (see preflight.hpp).
#include "preflight.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/heartbeat_t.hpp"

namespace lcmloc::preflight {

namespace {
using Clock = std::chrono::steady_clock;

/// The interface of the most specific route to group in the main table (/proc/net/route), "" when
/// none is listed there.
std::string routeInterface(const in_addr& group) {
  std::ifstream in("/proc/net/route");
  std::string line, best;
  std::getline(in, line);  // header
  int best_bits = -1;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string iface;
    unsigned dest = 0, gw = 0, flags = 0, refcnt = 0, use = 0, metric = 0, mask = 0;
    if (!(f >> iface >> std::hex >> dest >> gw >> flags >> std::dec >> refcnt >> use >> metric >> std::hex >> mask))
      continue;
    if ((group.s_addr & mask) != (dest & mask)) continue;  // (both in network byte order)
    const int bits = __builtin_popcount(mask);
    if (bits > best_bits) {
      best_bits = bits;
      best = iface;
    }
  }
  return best;
}

/// The interface's flags (IFF_UP, IFF_MULTICAST ...); 0 when it is not found.
unsigned interfaceFlags(const std::string& iface) {
  ifaddrs* list = nullptr;
  unsigned flags = 0;
  if (::getifaddrs(&list) != 0) return 0;
  for (ifaddrs* i = list; i; i = i->ifa_next)
    if (iface == i->ifa_name) flags |= i->ifa_flags;
  ::freeifaddrs(list);
  return flags;
}
}  // namespace

UdpmUrl parseUdpm(const std::string& url) {
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0)
    throw app::UsageError("--lcm-url '" + url + "': the checks are for udpm:// URLs (udpm://GROUP:PORT?ttl=1...)");
  const std::string rest = url.substr(scheme.size(), url.find('?') == std::string::npos
                                                         ? std::string::npos
                                                         : url.find('?') - scheme.size());
  UdpmUrl u;
  const auto colon = rest.find(':');
  u.group = rest.substr(0, colon);
  u.port = colon == std::string::npos ? 7667 : std::atoi(rest.c_str() + colon + 1);
  in_addr a{};
  if (::inet_pton(AF_INET, u.group.c_str(), &a) != 1 || !IN_MULTICAST(ntohl(a.s_addr)) || u.port <= 0 ||
      u.port > 65535)
    throw app::UsageError("--lcm-url '" + url + "': expected udpm://GROUP:PORT with an IPv4 multicast group "
                          "(224.0.0.0/4) and a port");
  if (const auto ttl = bus::urlOption(url, "ttl")) u.ttl = std::atoi(ttl->c_str());
  u.recv_buf_size = bus::receiveBufferOf(url);
  return u;
}

Finding checkRoute(const UdpmUrl& u, bool multi_host) {
  Finding f{Finding::Ok, "route"};
  const std::string add = "as root: ip route add 224.0.0.0/4 dev IFACE (the vehicle network's interface; lo when "
                          "every process runs on this host), and make it permanent in the network configuration "
                          "(docs/network.md)";
  // connect() on a UDP socket asks the kernel's routing table, as a send would.
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return {Finding::Fail, "route", std::string("no UDP socket: ") + std::strerror(errno), ""};
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<uint16_t>(u.port));
  ::inet_pton(AF_INET, u.group.c_str(), &to.sin_addr);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
    const int e = errno;
    ::close(fd);
    return {Finding::Fail, "route",
            fmt::format("no route to the multicast group {} ({}): LCM cannot send or start", u.group, std::strerror(e)),
            add};
  }
  ::close(fd);
  const std::string iface = routeInterface(to.sin_addr);
  f.what = fmt::format("{} goes out via {}", u.group, iface.empty() ? "a route outside the main table" : iface);
  const unsigned flags = iface.empty() ? IFF_UP : interfaceFlags(iface);
  if ((flags & IFF_UP) == 0) {
    f.level = Finding::Fail;
    f.what += ", which is down";
    f.fix = "as root: ip link set " + iface + " up";
  } else if (iface != "lo" && (flags & IFF_MULTICAST) == 0) {  // (lo carries multicast without the flag)
    f.level = Finding::Warn;
    f.what += ", which has no MULTICAST flag";
    f.fix = "as root: ip link set " + iface + " multicast on";
  } else if (multi_host && iface == "lo") {
    f.level = Finding::Fail;
    f.what += ": the other hosts do not hear it";
    f.fix = "route 224.0.0.0/4 to the vehicle network's interface: " + add;
  }
  return f;
}

Finding checkTtl(const UdpmUrl& u, bool multi_host) {
  if (u.ttl == 0 && multi_host)
    return {Finding::Fail, "ttl", "ttl=0: messages stay on this host",
            "use ttl=1 in --lcm-url (udpm://" + u.group + ":" + std::to_string(u.port) + "?ttl=1&...) on every host"};
  if (u.ttl == 0) return {Finding::Ok, "ttl", "ttl=0: this host only (--multi-host for a vehicle network)", ""};
  if (u.ttl == 1) return {Finding::Ok, "ttl", "ttl=1: the hosts on this network segment", ""};
  return {Finding::Warn, "ttl",
          fmt::format("ttl={}: messages may cross multicast routers and leave the vehicle network", u.ttl),
          "use ttl=1 unless the system spans routed networks"};
}

Finding checkReceiveBuffer(const UdpmUrl& u, const std::string& rmem_max_file) {
  const long long rmem_max = bus::kernelRmemMax(rmem_max_file);
  if (u.recv_buf_size <= 0)
    return {Finding::Warn, "rmem_max",
            "the URL asks for no receive buffer (recv_buf_size): the kernel's default drops bursts",
            "add recv_buf_size=4194304 to the URL (lcmloc-launcher adds its recv_buf_size to the children's)"};
  if (rmem_max < 0)
    return {Finding::Warn, "rmem_max", "cannot read " + rmem_max_file, "check net.core.rmem_max by hand: sysctl net.core.rmem_max"};
  if (rmem_max < u.recv_buf_size)
    return {Finding::Fail, "rmem_max",
            fmt::format("net.core.rmem_max = {} ({}) is less than the recv_buf_size={} the URL asks for: the kernel "
                        "gives LCM the smaller buffer and bursts are lost",
                        rmem_max, rmem_max_file, u.recv_buf_size),
            fmt::format("as root: sysctl -w net.core.rmem_max={0}, and to keep it: echo net.core.rmem_max={0} > "
                        "/etc/sysctl.d/60-lcm.conf",
                        u.recv_buf_size)};
  return {Finding::Ok, "rmem_max", fmt::format("net.core.rmem_max = {} >= recv_buf_size={}", rmem_max, u.recv_buf_size), ""};
}

Finding selfTest(const std::string& url) {
  const std::string fix = "fix the findings above (route, ttl); LCM's own message on stderr says more";
  std::unique_ptr<lcm::LCM> lcm;
  try {
    lcm = std::make_unique<lcm::LCM>(url);
  } catch (const std::exception& e) {
    return {Finding::Fail, "self-test", std::string("LCM did not start: ") + e.what(), fix};
  }
  // good() can be true although the self-test failed: the file descriptor tells (GUIDE).
  if (!lcm->good() || lcm->getFileno() < 0) return {Finding::Fail, "self-test", "LCM did not start on " + url, fix};
  struct Echo {
    bool heard = false;
    void on(const lcm::ReceiveBuffer*, const std::string&) { heard = true; }
  } echo;
  const std::string channel = "LCMLOC_PREFLIGHT_" + std::to_string(::getpid());
  lcm->subscribe(channel, &Echo::on, &echo);
  const auto deadline = Clock::now() + std::chrono::seconds(1);
  const uint8_t byte = 1;
  lcm->publish(channel, &byte, 1);
  while (!echo.heard && Clock::now() < deadline) lcm->handleTimeout(50);
  if (!echo.heard)
    return {Finding::Fail, "self-test", "a message published on " + channel + " did not come back within 1 s",
            "look for a firewall (nftables, iptables) dropping UDP to the URL's port, and for multicast "
            "loopback turned off: see docs/network.md"};
  return {Finding::Ok, "self-test", "LCM started and heard its own message", ""};
}

std::vector<Finding> checkClocks(const app::ProcessTable& table, double max_offset) {
  std::vector<Finding> out;
  const auto clocks = table.clocks();
  if (clocks.empty()) {
    out.push_back({Finding::Note, "clock", "no heartbeat heard: clock offsets between hosts not estimated", ""});
    return out;
  }
  for (const auto& [host, c] : clocks) {
    const std::string what = fmt::format("{:+.1f} ms ({} heartbeats, spread {:.1f} ms; > 0: that host is behind "
                                         "this one, network latency included)",
                                         c.offset * 1e3, c.samples, c.spread * 1e3);
    if (std::abs(c.offset) > max_offset)
      out.push_back({Finding::Fail, "clock " + host, what,
                     fmt::format("synchronise the hosts' clocks (chrony on every host against one server, or PTP: "
                                 "linuxptp's ptp4l + phc2sys) to well under {:.0f} ms; message times stamped on "
                                 "different hosts are fused in one order (docs/network.md)",
                                 max_offset * 1e3)});
    else
      out.push_back({Finding::Ok, "clock " + host, what, ""});
  }
  return out;
}

std::vector<Finding> listen(const Options& opts) {
  std::vector<Finding> out;
  lcm::LCM lcm(opts.url);
  if (!lcm.good() || lcm.getFileno() < 0) return out;  // (the self-test said so)
  struct Heard {
    std::map<std::string, int64_t> count;
    app::ProcessTable table;
    std::string heartbeat;
    void on(const lcm::ReceiveBuffer* rb, const std::string& ch) {
      ++count[ch];
      if (ch != heartbeat) return;
      lcmloc::heartbeat_t m;
      if (m.decode(rb->data, 0, static_cast<int>(rb->data_size)) >= 0) table.observe(m, rb->recv_utime);
    }
  } heard;
  heard.heartbeat = opts.heartbeat_channel;
  lcm.subscribe(".*", &Heard::on, &heard)->setQueueCapacity(0);
  const auto deadline = Clock::now() + std::chrono::duration<double>(opts.listen);
  std::set<std::string> want(opts.expect.begin(), opts.expect.end());
  while (Clock::now() < deadline && !app::stopRequested()) lcm.handleTimeout(50);
  for (const auto& ch : want) {
    const auto it = heard.count.find(ch);
    if (it == heard.count.end())
      out.push_back({Finding::Fail, "channel " + ch, fmt::format("no publisher within {:.1f} s", opts.listen),
                     "is the process that publishes it running and healthy (lcmloc-ctl status)? On another host: "
                     "run lcmloc-preflight --multi-host there (route, ttl=1); a channel name spelled alike in "
                     "every config?"});
    else
      out.push_back({Finding::Ok, "channel " + ch, fmt::format("{} messages in {:.1f} s", it->second, opts.listen), ""});
  }
  for (auto& f : checkClocks(heard.table, opts.max_clock_offset)) out.push_back(std::move(f));
  return out;
}

std::vector<Finding> runAll(const Options& opts) {
  const UdpmUrl u = parseUdpm(opts.url);
  std::vector<Finding> out{checkRoute(u, opts.multi_host), checkTtl(u, opts.multi_host),
                           checkReceiveBuffer(u, opts.rmem_max_file)};
  if (out.front().level == Finding::Fail && out.front().what.find("no route") != std::string::npos) {
    out.push_back({Finding::Fail, "self-test", "not tried: no route (LCM cannot start)", "fix the route first"});
    return out;
  }
  out.push_back(selfTest(opts.url));
  if (out.back().level == Finding::Fail) return out;
  if (opts.listen > 0)
    for (auto& f : listen(opts)) out.push_back(std::move(f));
  return out;
}

std::string format(const std::vector<Finding>& findings) {
  static const char* const kLevel[] = {"ok", "note", "WARN", "FAIL"};
  std::string t;
  for (const auto& f : findings) {
    t += fmt::format("{:<5} {}: {}\n", kLevel[f.level], f.check, f.what);
    if (!f.fix.empty()) t += "      -> " + f.fix + "\n";
  }
  return t;
}

}  // namespace lcmloc::preflight
