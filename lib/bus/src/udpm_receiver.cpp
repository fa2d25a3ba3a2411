#include "lcmloc/bus/udpm_receiver.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>

#include <spdlog/spdlog.h>

#include "lcmloc/bus/transport.hpp"

namespace lcmloc::bus {

namespace {

constexpr uint32_t kMagicShort = 0x4c433032;  // "LC02"
constexpr uint32_t kMagicLong = 0x4c433033;   // "LC03"
constexpr std::size_t kShortHeader = 8;
constexpr std::size_t kLongHeader = 20;
constexpr std::size_t kDatagramMax = 65536;
constexpr int kBatch = 16;

uint32_t be32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}
uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

/// The channel at p (NUL-terminated within n bytes, at most kMaxChannel long), else nullopt.
std::optional<std::string_view> channelAt(const uint8_t* p, std::size_t n) {
  const auto* end = static_cast<const uint8_t*>(std::memchr(p, 0, n));
  if (!end) return std::nullopt;
  const auto len = static_cast<std::size_t>(end - p);
  if (len == 0 || len > UdpmAssembler::kMaxChannel) return std::nullopt;
  return std::string_view(reinterpret_cast<const char*>(p), len);
}

std::string sysError(const std::string& what) { return what + ": " + std::strerror(errno); }

}  // namespace

std::optional<UdpmAddress> parseUdpmUrl(const std::string& url) {
  static const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) return std::nullopt;
  const auto q = url.find('?');
  std::string net = url.substr(scheme.size(), q == std::string::npos ? std::string::npos : q - scheme.size());
  if (net.empty()) net = "239.255.76.67:7667";
  UdpmAddress a;
  const auto colon = net.find(':');
  const std::string host = net.substr(0, colon);
  in_addr group{};
  if (inet_aton(host.c_str(), &group) == 0) return std::nullopt;
  a.group = ntohl(group.s_addr);
  a.port = 0;  // LCM leaves the port 0 when the URL gives none
  if (colon != std::string::npos) {
    const std::string port = net.substr(colon + 1);
    char* end = nullptr;
    const long p = std::strtol(port.c_str(), &end, 0);
    if (port.empty() || *end != '\0' || p < 0 || p > 65535) return std::nullopt;
    a.port = static_cast<uint16_t>(p);
  }
  if (q == std::string::npos) return a;
  for (std::size_t pos = q + 1; pos < url.size();) {
    std::size_t end = url.find('&', pos);
    if (end == std::string::npos) end = url.size();
    const std::string opt = url.substr(pos, end - pos);
    pos = end + 1;
    if (opt.empty()) continue;
    const auto eq = opt.find('=');
    const std::string key = opt.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : opt.substr(eq + 1);
    if (key == "recv_buf_size") {
      a.recv_buf_size = static_cast<int>(std::strtol(value.c_str(), nullptr, 0));
    } else if (key != "ttl") {
      return std::nullopt;
    }
  }
  return a;
}

void UdpmAssembler::drop(std::map<uint64_t, Partial>::iterator it) {
  pending_bytes_ -= it->second.data.size();
  pending_.erase(it);
}

UdpmAssembler::Result UdpmAssembler::add(const uint8_t* p, std::size_t n, uint64_t sender, int64_t recv_utime,
                                         const std::function<bool(std::string_view)>& wanted, UdpmMessage* out) {
  if (n < kShortHeader) return Result::Bad;
  const uint32_t magic = be32(p);
  if (magic == kMagicShort) {
    const auto channel = channelAt(p + kShortHeader, n - kShortHeader);
    if (!channel) return Result::Bad;
    if (!wanted(*channel)) return Result::Ignored;
    const std::size_t at = kShortHeader + channel->size() + 1;
    *out = UdpmMessage{*channel, p + at, n - at, recv_utime};
    return Result::Message;
  }
  if (magic != kMagicLong || n < kLongHeader) return Result::Bad;
  const uint32_t seqno = be32(p + 4);
  const uint32_t size = be32(p + 8);
  const uint32_t offset = be32(p + 12);
  const uint16_t number = be16(p + 16);
  const uint16_t count = be16(p + 18);
  const uint8_t* body = p + kLongHeader;
  std::size_t body_size = n - kLongHeader;

  auto it = pending_.find(sender);
  // A fragment of another message from this sender: the one pending is lost (as in LCM).
  if (it != pending_.end() && (it->second.seqno != seqno || it->second.data.size() != size)) {
    drop(it);
    it = pending_.end();
  }
  if (size > kMaxMessage || count == 0 || number >= count) return Result::Bad;
  if (it == pending_.end()) {
    if (number != 0) return Result::Partial;  // its first fragment was missed: nothing to add to
    const auto channel = channelAt(body, body_size);
    if (!channel) return Result::Bad;
    if (!wanted(*channel)) return Result::Ignored;
    while (!pending_.empty() &&
           (pending_.size() >= kMaxPendingSenders || pending_bytes_ + size > kMaxPendingBytes)) {
      auto oldest = pending_.begin();
      for (auto j = pending_.begin(); j != pending_.end(); ++j)
        if (j->second.started < oldest->second.started) oldest = j;
      drop(oldest);
    }
    if (size > kMaxPendingBytes) return Result::Bad;
    Partial part;
    part.seqno = seqno;
    part.channel = std::string(*channel);
    part.data.resize(size);
    part.got.assign(count, false);
    part.remaining = count;
    part.started = arrivals_++;
    pending_bytes_ += size;
    it = pending_.emplace(sender, std::move(part)).first;
  }
  Partial& part = it->second;
  if (number == 0) {
    const auto channel = channelAt(body, body_size);
    if (!channel || *channel != part.channel) {
      drop(it);
      return Result::Bad;
    }
    body += channel->size() + 1;
    body_size -= channel->size() + 1;
  }
  if (part.got.size() != count || uint64_t{offset} + body_size > part.data.size()) {
    drop(it);
    return Result::Bad;
  }
  if (part.got[number]) return Result::Partial;  // a duplicate
  if (body_size) std::memcpy(part.data.data() + offset, body, body_size);
  part.got[number] = true;
  if (--part.remaining > 0) return Result::Partial;
  done_ = std::move(part.data);
  done_channel_ = std::move(part.channel);
  pending_bytes_ -= size;
  pending_.erase(it);
  *out = UdpmMessage{done_channel_, done_.data(), done_.size(), recv_utime};
  return Result::Message;
}

struct UdpmReceiver::Batch {
  mmsghdr msgs[kBatch];
  iovec iov[kBatch];
  sockaddr_in from[kBatch];
  alignas(cmsghdr) char control[kBatch][CMSG_SPACE(sizeof(timeval))];
};

UdpmReceiver::UdpmReceiver(const UdpmAddress& a) {
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw TransportError(sysError("cannot open an LCM receive socket"));
  auto fail = [this](const std::string& what) {
    const std::string msg = sysError(what);
    ::close(fd_);
    fd_ = -1;
    throw TransportError(msg);
  };
  int one = 1;
  if (setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0) fail("setsockopt(SO_REUSEADDR)");
  if (a.recv_buf_size > 0 && setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &a.recv_buf_size, sizeof a.recv_buf_size) < 0)
    fail("setsockopt(SO_RCVBUF)");
  socklen_t len = sizeof rcvbuf_;
  getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf_, &len);
  // (the kernel reports twice what it was asked, for its bookkeeping; it caps the request at rmem_max)
  if (a.recv_buf_size > 0 && rcvbuf_ < a.recv_buf_size)
    spdlog::warn("the LCM receive buffer is {} bytes, less than the {} asked for (net.core.rmem_max caps it)",
                 rcvbuf_, a.recv_buf_size);
  setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_ANY);
  addr.sin_port = htons(a.port);
  if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0)
    fail("cannot bind the LCM receive socket to port " + std::to_string(a.port));
  ip_mreq mreq{};
  mreq.imr_multiaddr.s_addr = htonl(a.group);
  mreq.imr_interface.s_addr = htonl(INADDR_ANY);
  if (setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) < 0) {
    in_addr g{};
    g.s_addr = htonl(a.group);
    fail(std::string("cannot join the multicast group ") + inet_ntoa(g));
  }
  buffers_.resize(kBatch * kDatagramMax);
}

UdpmReceiver::~UdpmReceiver() {
  if (fd_ >= 0) ::close(fd_);
}

int UdpmReceiver::handle(int timeout_ms, const Wanted& wanted, const Dispatch& dispatch, int max_datagrams) {
  using Clock = std::chrono::steady_clock;
  const auto until = Clock::now() + std::chrono::milliseconds(std::max(timeout_ms, 0));
  for (;;) {
    if (timeout_ms != 0) {
      int wait = -1;
      if (timeout_ms > 0) {
        const auto left = std::chrono::ceil<std::chrono::milliseconds>(until - Clock::now()).count();
        wait = static_cast<int>(std::max<int64_t>(left, 0));
      }
      pollfd pfd{fd_, POLLIN, 0};
      const int r = ::poll(&pfd, 1, wait);
      if (r < 0) return -1;  // (a signal: the caller looks at its stop flag)
      if (r == 0) return 0;
    }
    int dispatched = 0;
    const int read = readSome(wanted, dispatch, max_datagrams, &dispatched);
    if (read < 0) return -1;
    // As lcm_handle_timeout: a datagram no one subscribes to does not end the wait.
    if (dispatched > 0 || timeout_ms == 0) return read;
    if (timeout_ms > 0 && Clock::now() >= until) return 0;
  }
}

int UdpmReceiver::readSome(const Wanted& wanted, const Dispatch& dispatch, int max_datagrams, int* dispatched) {
  Batch b;
  int total = 0;
  while (total < max_datagrams) {
    const int want = std::min(kBatch, max_datagrams - total);
    for (int i = 0; i < want; ++i) {
      b.iov[i] = iovec{buffers_.data() + static_cast<std::size_t>(i) * kDatagramMax, kDatagramMax};
      b.msgs[i].msg_hdr = msghdr{};
      b.msgs[i].msg_hdr.msg_name = &b.from[i];
      b.msgs[i].msg_hdr.msg_namelen = sizeof(sockaddr_in);
      b.msgs[i].msg_hdr.msg_iov = &b.iov[i];
      b.msgs[i].msg_hdr.msg_iovlen = 1;
      b.msgs[i].msg_hdr.msg_control = b.control[i];
      b.msgs[i].msg_hdr.msg_controllen = sizeof b.control[i];
      b.msgs[i].msg_len = 0;
    }
    const int got = recvmmsg(fd_, b.msgs, static_cast<unsigned>(want), MSG_DONTWAIT, nullptr);
    if (got < 0) {
      if (errno == EINTR && total == 0) return -1;
      break;  // EAGAIN: the socket is drained
    }
    for (int i = 0; i < got; ++i) {
      const msghdr& h = b.msgs[i].msg_hdr;
      int64_t utime = 0;
      for (cmsghdr* c = CMSG_FIRSTHDR(&h); c; c = CMSG_NXTHDR(const_cast<msghdr*>(&h), c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
          timeval tv;
          std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
          utime = int64_t{tv.tv_sec} * 1000000 + tv.tv_usec;
        }
      }
      if (!utime) utime = wallMicros();
      const uint64_t sender = (uint64_t{ntohl(b.from[i].sin_addr.s_addr)} << 16) | ntohs(b.from[i].sin_port);
      UdpmMessage m;
      if (assembler_.add(static_cast<const uint8_t*>(b.iov[i].iov_base), b.msgs[i].msg_len, sender, utime, wanted,
                         &m) == UdpmAssembler::Result::Message) {
        dispatch(m);
        ++*dispatched;
      }
    }
    total += got;
    if (got < want) break;
  }
  return total;
}

}  // namespace lcmloc::bus
