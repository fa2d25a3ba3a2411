// lcmloc-logger: records channels to a standard LCM log (lcm-logplayer plays it). The LCM
// thread only enqueues; a writer thread writes. At exit: per-channel counts, sequence gaps and
// queue drops. Flushes and closes cleanly on SIGINT/SIGTERM.
#include <spdlog/spdlog.h>

#include "lcmloc/common/config.hpp"
#include "lcmloc/common/process.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "log_writer.hpp"

using namespace lcmloc;

namespace {

/// One regex for LCM (which anchors it): empty = every channel.
std::string channelRegex(const std::vector<std::string>& regexes) {
  if (regexes.empty()) return ".*";
  std::string r;
  for (std::size_t i = 0; i < regexes.size(); ++i) r += (i ? "|" : "") + ("(" + regexes[i] + ")");
  return r;
}

struct ChannelStats { int64_t count = 0, gaps = 0; };

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-logger: records LCM channels to a log file that lcm-logplayer plays"};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);
  std::string output;
  std::vector<std::string> channels;
  app.add_option("--output,-o", output, "log file (overrides logger.output)");
  app.add_option("--channel", channels, "channel regex to record (repeatable; overrides logger.channels)");

  return common::runProcess(app, argc, argv, opts, "lcmloc-logger", [&] {
    const auto cfg = common::loadSystemConfig(opts.config);
    const std::string path = output.empty() ? cfg.logger.output : output;
    const std::string regex = channelRegex(channels.empty() ? cfg.logger.channels : channels);
    const std::string hb_channel = cfg.channels.heartbeat;

    logger::LogWriter writer(path, static_cast<std::size_t>(cfg.logger.queue_capacity));
    common::Bus bus(opts.lcm_url);
    std::map<std::string, ChannelStats> stats;
    common::SeqTracker gaps;  // keyed by channel (HEARTBEAT: by channel and process)
    int64_t received = 0;
    bus.subscribeRaw(regex, [&](const std::string& ch, const uint8_t* data, std::size_t size, int64_t recv) {
      ++received;
      ++stats[ch].count;
      int64_t seq = 0;
      if (logger::readSeq(data, size, &seq)) {
        std::string key = ch;
        if (ch == hb_channel) {  // many publishers share HEARTBEAT: track each one
          lcmloc::heartbeat_t hb;
          if (hb.decode(data, 0, static_cast<int>(size)) >= 0) key = ch + "[" + hb.process + "]";
        }
        if (int64_t missing = gaps.observe(key, seq)) {
          stats[ch].gaps += missing;
          spdlog::warn("{}: {} message(s) missing before seq {}", key, missing, seq);
        }
      }
      writer.push({ch, std::vector<uint8_t>(data, data + size), recv});
    });
    common::Heartbeat hb(bus, hb_channel, "lcmloc-logger", [&] {
      return common::Heartbeat::Counters{{"received", received}, {"written", writer.written()},
                                         {"dropped", writer.dropped()}, {"gaps", gaps.gaps()}};
    });
    spdlog::info("recording '{}' to {}", regex, path);
    while (!common::stopRequested()) {
      hb.tick();
      bus.handle(100);
    }
    while (bus.handle(0) > 0) {}  // take what already arrived
    hb.publish("stopping");
    while (bus.handle(0) > 0) {}  // (our own last heartbeat included)
    writer.close();

    const auto drops = writer.droppedByChannel();
    for (const auto& [ch, s] : stats) {
      const auto d = drops.count(ch) ? drops.at(ch) : 0;
      spdlog::info("  {:<24} {:>8} messages, {} sequence gaps, {} dropped", ch, s.count, s.gaps, d);
    }
    spdlog::info("recorded {} of {} messages on {} channels to {}; {} sequence gaps, {} dropped, {} write errors",
                 writer.written(), received, stats.size(), path, gaps.gaps(), writer.dropped(), writer.writeErrors());
    return writer.writeErrors() > 0 ? common::kExitRuntimeError : common::kExitOk;
  });
}
