// Fuzz target: what the fusion daemon does with the bytes on its input channels. Each input
// picks a system config (byte 0, low 7 bits) and is a sequence of messages, each
// [channel][length: 2 bytes, big-endian][payload], the channel one of those the daemon
// subscribes to (every sensor input of kSensorInputs and FUSION_CONTROL; any byte, modulo their
// number). With byte 0's high bit clear, a fresh daemon over the MemoryBus takes them in: the
// bus's decoder, the intake's bus::toInput conversion and seq checks, the engine; then every
// pose it published must decode and be finite. With it set, only the daemon's intake does (each
// type's decoder, bus::toInput, the seq checks): many more inputs per second.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "daemon/daemon.hpp"
#include "fuzz_util.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace {

using namespace lcmloc;

/// Decodes a message of one channel's type and hands it to the intake (nothing when it does
/// not decode, as the bus does).
using Take = void (*)(fusion::DaemonIntake&, const std::string&, const uint8_t*, std::size_t, fusion::IntakeItem&);

template <typename Lcm>
void take(fusion::DaemonIntake& intake, const std::string& ch, const uint8_t* data, std::size_t size,
          fusion::IntakeItem& item) {
  Lcm m;
  try {
    if (bus::decodeMessage(m, data, size) < 0) return;
  } catch (const std::exception&) {  // bad_alloc, length_error: the bus's "cannot decode"
    return;
  }
  if constexpr (std::is_same_v<Lcm, lcmloc::fusion_control_t>)
    intake.control(ch, m, item);
  else
    intake.take(ch, m, item);
}

struct Setup {
  app::SystemConfig cfg;
  std::vector<std::string> channels;  ///< every channel the daemon subscribes to
  std::vector<Take> takes;            ///< the intake of each
};

std::vector<Setup> setups() {
  std::vector<Setup> out;
  for (const char* name : {"paper.yaml", "gps_paper.yaml", "ins_vision_paper.yaml", "landmark_paper.yaml"}) {
    Setup s;
    s.cfg = app::loadSystemConfig(std::string(LCMLOC_SOURCE_DIR "/config/") + name);
    fusion::forEachSensorInput([&](const auto& input) {
      using Lcm = typename std::decay_t<decltype(input)>::lcm_type;
      for (const auto& ch : input.channels(s.cfg.channels)) {
        s.channels.push_back(ch);
        s.takes.push_back(&take<Lcm>);
      }
    });
    s.channels.push_back(s.cfg.channels.control);
    s.takes.push_back(&take<lcmloc::fusion_control_t>);
    out.push_back(std::move(s));
  }
  return out;
}

void checkPoses(const bus::MemoryBus& bus) {
  for (const auto& m : bus.published()) {
    if (m.channel.rfind("POSE", 0) != 0) continue;
    lcmloc::pose_t p;
    if (p.decode(m.data.data(), 0, static_cast<int>(m.data.size())) != static_cast<int>(m.data.size()))
      fuzz::finding("a pose on " + m.channel + " does not decode");
    for (double v : p.state)
      if (!std::isfinite(v)) fuzz::finding("a state on " + m.channel + " is not finite");
    for (const auto& row : p.covariance)
      for (double v : row)
        if (!std::isfinite(v)) fuzz::finding("a covariance on " + m.channel + " is not finite");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const std::vector<Setup> kSetups = [] {
    fuzz::quiet();
    return setups();
  }();
  if (size < 1) return 0;
  const Setup& s = kSetups[(data[0] & 0x7f) % kSetups.size()];
  const bool intake_only = (data[0] & 0x80) != 0;
  // The messages: (channel index, payload).
  std::vector<std::pair<std::size_t, std::vector<uint8_t>>> messages;
  std::size_t i = 1;
  while (i < size) {
    const std::size_t channel = data[i] % s.channels.size();
    std::size_t len = 0;
    if (i + 3 <= size) len = (std::size_t{data[i + 1]} << 8) | data[i + 2];
    i = std::min(i + 3, size);
    len = std::min(len, size - i);
    messages.emplace_back(channel, std::vector<uint8_t>(data + i, data + i + len));
    i += len;
  }
  if (intake_only) {
    fusion::DaemonIntake intake(s.cfg);
    fusion::IntakeItem item;
    for (const auto& [channel, bytes] : messages)
      s.takes[channel](intake, s.channels[channel], bytes.data(), bytes.size(), item);
    return 0;
  }
  bus::MemoryBus bus;
  fusion::FusionDaemon daemon(s.cfg, bus);
  for (auto& [channel, bytes] : messages) bus.inject(s.channels[channel], std::move(bytes));
  bus.deliverAll();
  daemon.shutdown();
  bus.deliverAll();
  checkPoses(bus);
  static const bool verbose = std::getenv("LCMLOC_FUZZ_VERBOSE") != nullptr;
  if (verbose)
    std::fprintf(stderr, "%lld messages in, %lld rejected, %zu published\n",
                 static_cast<long long>(daemon.messagesIn()), static_cast<long long>(daemon.rejected()),
                 bus.published().size());
  return 0;
}
