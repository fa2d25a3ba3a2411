// Fuzz target: the udpm datagrams a Bus that receives on its own socket reassembles
// (bus::UdpmAssembler, udpm_receiver.hpp). Each input is a sequence of datagrams, each
// [sender: 1 byte][length: 2 bytes, big-endian][datagram], from up to 256 senders. A channel
// that begins with 'X' is one no one subscribes to. Every message that comes out must have a
// channel of 1..63 characters without NUL that someone subscribes to, a short message's payload
// must lie inside its datagram, every byte of it is read (ASan sees a read out of bounds), and
// the partial messages must stay within their memory bound.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "fuzz_util.hpp"
#include "lcmloc/bus/udpm_receiver.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using lcmloc::bus::UdpmAssembler;
  UdpmAssembler a;
  const auto wanted = [](std::string_view ch) { return ch.empty() || ch[0] != 'X'; };
  unsigned sum = 0;
  for (std::size_t pos = 0; pos + 3 <= size;) {
    const uint64_t sender = data[pos];
    const std::size_t n = std::min<std::size_t>((std::size_t{data[pos + 1]} << 8) | data[pos + 2], size - pos - 3);
    const uint8_t* datagram = data + pos + 3;
    pos += 3 + n;
    lcmloc::bus::UdpmMessage m;
    const bool message = a.add(datagram, n, sender, 1, wanted, &m) == UdpmAssembler::Result::Message;
    if (a.pendingBytes() > UdpmAssembler::kMaxPendingBytes || a.pendingSenders() > UdpmAssembler::kMaxPendingSenders)
      lcmloc::fuzz::finding("partial messages beyond their bound");
    if (!message) continue;
    if (m.channel.empty() || m.channel.size() > UdpmAssembler::kMaxChannel ||
        m.channel.find('\0') != std::string_view::npos)
      lcmloc::fuzz::finding("a message with a bad channel");
    if (m.size > 0 && !m.data) lcmloc::fuzz::finding("a message without its data");
    const bool short_message = n >= 4 && datagram[3] == 0x32;
    if (short_message && (m.data < datagram || m.data + m.size != datagram + n))
      lcmloc::fuzz::finding("a short message's payload outside its datagram");
    if (!wanted(m.channel)) lcmloc::fuzz::finding("a message no one subscribes to reassembled");
    for (std::size_t i = 0; i < m.size; ++i) sum += m.data[i];
  }
  return static_cast<int>(sum & 0u);
}
