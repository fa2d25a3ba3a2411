#include "lcmloc/replay/replay.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <memory>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "daemon/daemon.hpp"
#include "lcmloc/core/text.hpp"
#include "lcmloc/eval/read_ahead.hpp"
#include "lcmloc/replay/log_bus.hpp"

namespace lcmloc::replay {

bool isDaemonOutput(const common::ChannelConfig& ch, const std::string& c) {
  if (c == ch.pose || c == ch.gate || c == ch.status) return true;
  // shadow filters: POSE_<TYPE>
  const std::size_t n = ch.pose.size();
  if (c.size() > n + 1 && c[n] == '_' && c.compare(0, n, ch.pose) == 0) return true;
  return false;
}

namespace {

/// Feeds every event of the scanner (LogScanner, or ReadAheadScanner: the same events) to the
/// daemon over bus; fills in what the scanner and the daemon counted.
template <typename Scanner>
void replayEvents(Scanner& scanner, LogBus& bus, fusion::FusionDaemon& daemon, const common::SystemConfig& cfg,
                  const ReplayOptions& opts, ReplayResult& r) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  r.file_size = scanner.fileSize();
  auto next_progress = t0 + std::chrono::duration<double>(opts.progress_period_s);
  std::size_t issues_reported = 0;
  // Whether the channel is one of the daemon's outputs, kept for the channel of the event before
  // (most events are on the same channel as the one before).
  std::string last_channel;
  bool last_is_output = false;
  while (true) {
    if ((scanner.eventsRead() & 255) == 0 && opts.stop && opts.stop()) {  // (every 256 events)
      r.interrupted = true;
      break;
    }
    if (!bus.writeError().empty()) break;  // the output cannot hold more
    const lcm::LogEvent* ev = scanner.next();
    for (; issues_reported < r.issues.size(); ++issues_reported) {
      const auto& is = r.issues[issues_reported];
      spdlog::warn("input log damaged: event {} at byte {}: {}", is.event_index, is.byte_offset, is.what);
    }
    if (!ev) break;
    if (last_channel.empty() || !core::sameText(ev->channel, last_channel)) {
      last_channel = ev->channel;
      last_is_output = isDaemonOutput(cfg.channels, ev->channel);
    }
    if (last_is_output) {
      ++r.old_outputs;  // the recorded run's estimates: never fed back, never copied
      continue;
    }
    if (opts.with_inputs && ev->channel != cfg.channels.heartbeat && ev->channel != "LCM_SELF_TEST") {
      bus.copy(ev->channel, ev->data, static_cast<std::size_t>(ev->datalen), ev->timestamp);
      ++r.copied;
    }
    if (bus.dispatch(ev->channel, ev->data, static_cast<std::size_t>(ev->datalen), ev->timestamp) > 0)
      ++r.dispatched;
    if (opts.progress_period_s > 0 && (scanner.eventsRead() & 1023) == 0 && Clock::now() >= next_progress) {
      next_progress = Clock::now() + std::chrono::duration<double>(opts.progress_period_s);
      const double pct = r.file_size > 0 ? 100.0 * static_cast<double>(scanner.position()) / r.file_size : 100.0;
      const double secs = std::chrono::duration<double>(Clock::now() - t0).count();
      spdlog::info("{:5.1f} %: {} events read, {} used, {} written ({:.0f} events/s)", pct, scanner.eventsRead(),
                   daemon.processed(), bus.written(), scanner.eventsRead() / std::max(secs, 1e-9));
    }
  }
  r.events_read = scanner.eventsRead();
  r.bytes_unreadable = scanner.bytesUnreadable();
  r.damaged = scanner.damaged();
}

}  // namespace

ReplayResult replayLog(const common::SystemConfig& cfg, const ReplayOptions& opts) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  ReplayResult r;
  if (!opts.output.empty()) common::refuseOutputOverInputs("--output", opts.output, {opts.input}, "input log");
  std::unique_ptr<eval::ReadAheadScanner> ahead;
  std::unique_ptr<eval::LogScanner> inline_scanner;
  if (opts.read_ahead)
    ahead = std::make_unique<eval::ReadAheadScanner>(opts.input, &r.issues);
  else
    inline_scanner = std::make_unique<eval::LogScanner>(opts.input, &r.issues);
  LogBus bus(opts.output);
  fusion::FusionDaemon daemon(cfg, bus);
  if (ahead)
    replayEvents(*ahead, bus, daemon, cfg, opts, r);
  else
    replayEvents(*inline_scanner, bus, daemon, cfg, opts, r);
  daemon.shutdown();
  bus.close();
  r.messages_in = daemon.messagesIn();
  r.used = daemon.processed();
  r.rejected = daemon.rejected();
  r.gaps = daemon.gaps();
  r.written = bus.written();
  r.write_error = bus.writeError();
  r.written_per_channel = bus.writtenPerChannel();
  r.final_filter = daemon.activeFilter();
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return r;
}

}  // namespace lcmloc::replay
