// lcmloc-logger: records channels to standard LCM log files (lcm-logplayer plays them). The LCM
// thread only enqueues; a writer thread writes (see log_writer.hpp). Rotation by size and time,
// SIGHUP starts a new file, fsync every flush period, clean close on SIGINT/SIGTERM, a clear
// error and exit 1 when the disk fills up. A new file that cannot be opened (SIGHUP, size, time)
// is reported (error log, LOGGER_STATUS state "rotate_failed", heartbeat counter) while the
// logger goes on recording into its current file, and tried again. Per-channel accounting from the messages' seq:
// upstream gaps apart from the logger's own drops, periodically on LOGGER_STATUS and at exit
// (for at most logger::kMaxChannels channels; the rest are counted as one bucket). Channel and
// process names from the bus are printed with their control characters as '?'.
#include <signal.h>
#include <sys/socket.h>

#include <atomic>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>

#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/logio/log_writer.hpp"
#include "lcmloc/logio/types.hpp"
#include "lcmloc/logger_status_t.hpp"

using namespace lcmloc;

namespace {

std::atomic<bool> g_hup{false};
extern "C" void onHup(int) { g_hup.store(true); }

/// One regex for LCM: empty = every channel. LCM anchors it as ^...$, which binds only the
/// first and the last alternative of A|B: the alternation is grouped, ((A)|(B)).
std::string channelRegex(const std::vector<std::string>& regexes) {
  if (regexes.empty()) return ".*";
  std::string r;
  for (std::size_t i = 0; i < regexes.size(); ++i) r += (i ? "|" : "") + ("(" + regexes[i] + ")");
  return "(" + r + ")";
}

/// Sizes the receive buffer of every UDP socket LCM opened (LCM 1.3.1 hides its socket, so they
/// are found among our file descriptors) to at least bytes: SO_RCVBUF (capped by the kernel at
/// net.core.rmem_max), then SO_RCVBUFFORCE (allowed with CAP_NET_ADMIN). Says what it got.
void sizeReceiveBuffer(const std::string& url, int bytes) {
  if (url.rfind("udpm://", 0) != 0) {
    spdlog::info("receive buffer: transport '{}' has no UDP receive buffer to size", url);
    return;
  }
  long long rmem_max = -1;
  std::ifstream("/proc/sys/net/core/rmem_max") >> rmem_max;
  int best = 0;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    const int fd = std::atoi(e.path().filename().c_str());
    int type = 0, have = 0;
    socklen_t len = sizeof type;
    if (::getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &len) != 0 || type != SOCK_DGRAM) continue;
    len = sizeof have;
    ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &have, &len);
    if (have / 2 < bytes) {  // Linux reports twice the size set (bookkeeping overhead)
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
      len = sizeof have;
      ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &have, &len);
      if (have / 2 < bytes) ::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof bytes);
      len = sizeof have;
      ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &have, &len);
    }
    best = std::max(best, have / 2);
  }
  if (best >= bytes)
    spdlog::info("receive buffer: {} bytes for bursts (logger.recv_buf_size; kernel net.core.rmem_max = {})", best,
                 rmem_max);
  else
    spdlog::warn("receive buffer: {} bytes, less than the {} asked for: the kernel caps it at net.core.rmem_max = {} "
                 "without CAP_NET_ADMIN; raise it (sysctl -w net.core.rmem_max={}) or bursts may be lost",
                 best, bytes, rmem_max, bytes);
}

struct ChannelStats { int64_t received = 0, gaps = 0, dropped = 0, ignored = 0; };

/// Sequences (channels, HEARTBEAT processes) whose seq is followed; a new one beyond is not.
constexpr std::size_t kMaxSequences = 1000;
/// Bytes of channel names listed in one logger_status_t; the channels beyond go into the
/// kOtherChannels row (LCM channel names on udpm are short, so kMaxChannels of them fit anyway;
/// this bounds the message for any transport: lcmloc's decoders refuse messages above 1 MiB).
constexpr std::size_t kStatusNameBytes = 256 * 1024;

/// The rows the status and the summary list: each channel with statistics of its own (at most
/// kMaxChannels, and names of at most name_bytes bytes in all), then kOtherChannels for the rest.
std::vector<std::pair<std::string, ChannelStats>> channelRows(const std::map<std::string, ChannelStats>& stats,
                                                               const ChannelStats& other, std::size_t name_bytes) {
  std::vector<std::pair<std::string, ChannelStats>> rows;
  ChannelStats rest = other;
  std::size_t bytes = 0;
  for (const auto& [ch, s] : stats) {
    if (bytes + ch.size() <= name_bytes) {
      bytes += ch.size();
      rows.emplace_back(ch, s);
    } else {
      rest.received += s.received;
      rest.gaps += s.gaps;
      rest.dropped += s.dropped;
      rest.ignored += s.ignored;
    }
  }
  if (rest.received > 0) rows.emplace_back(logger::kOtherChannels, rest);
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-logger: records LCM channels to log files that lcm-logplayer plays.\n"
               "SIGINT/SIGTERM: write what is queued, close and exit; SIGHUP: start a new file (one that cannot be "
               "opened is reported, and recording goes on into the current file; tried again at the next SIGHUP)."};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);
  std::string output;
  std::vector<std::string> channels;
  double max_mb = -1, max_seconds = -1, flush_period = -1;
  app.add_option("--output,-o", output,
                 "log file name pattern: strftime codes (%Y%m%d-%H%M%S) and {index} (overrides logger.output)");
  app.add_option("--channel", channels, "channel regex to record (repeatable; overrides logger.channels)");
  app.add_option("--max-file-mb", max_mb, "start a new file before one exceeds this many MB (overrides logger.max_file_bytes)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(s, v)) return s + " is not a number";
            return v == 0.0 || (v >= 1e-3 && v <= 1e9) ? "" : s + " is not 0 (off) or within [0.001, 1e9] MB";
          },
          "0 or MB in [0.001, 1e9]"));
  app.add_option("--max-file-seconds", max_seconds, "start a new file after this many seconds (overrides logger.max_file_seconds)")
      ->check(CLI::Range(common::kMaxFileSeconds.lo, common::kMaxFileSeconds.hi));
  app.add_option("--flush-period", flush_period, "fsync period in seconds (overrides logger.flush_period)")
      ->check(CLI::Range(common::kFlushPeriod.lo, common::kFlushPeriod.hi));
  bool overwrite = false;
  app.add_flag("--overwrite", overwrite,
               "replace an existing log file (default: keep it and write NAME-001.lcmlog, the first free name)");

  return common::runProcess(app, argc, argv, opts, "lcmloc-logger", [&] {
    const auto cfg = common::loadSystemConfig(opts.config);
    struct sigaction sa {};
    sa.sa_handler = onHup;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGHUP, &sa, nullptr);  // no SA_RESTART: the LCM wait returns at once
    std::signal(SIGXFSZ, SIG_IGN);     // a file size limit becomes EFBIG, handled like a full disk

    logger::WriterOptions wo;
    wo.pattern = output.empty() ? cfg.logger.output : output;
    if (std::error_code ec; std::filesystem::is_directory(wo.pattern, ec))
      throw common::ConfigError(output.empty() ? cfg.file : "--output", output.empty() ? "logger.output" : "",
                                "'" + wo.pattern + "' is a directory: give a file name in it, e.g. '" +
                                    (std::filesystem::path(wo.pattern) / "run.lcmlog").string() + "'");
    wo.capacity = static_cast<std::size_t>(cfg.logger.queue_capacity);
    wo.queue_bytes = cfg.logger.queue_bytes;
    wo.max_file_bytes = max_mb >= 0 ? static_cast<int64_t>(max_mb * 1e6) : cfg.logger.max_file_bytes;
    wo.max_file_seconds = max_seconds >= 0 ? max_seconds : cfg.logger.max_file_seconds;
    wo.flush_period = flush_period > 0 ? flush_period : cfg.logger.flush_period;
    wo.overwrite = overwrite;
    const std::string regex = channelRegex(channels.empty() ? cfg.logger.channels : channels);
    try {
      std::regex check(regex, std::regex::extended);  // LCM compiles it as a POSIX extended regex
    } catch (const std::regex_error& e) {
      throw common::ConfigError(channels.empty() ? cfg.file : "--channel", channels.empty() ? "logger.channels" : "",
                                "bad channel regex '" + regex + "': " + e.what());
    }
    const std::string hb_channel = cfg.channels.heartbeat;
    const std::string status_channel = cfg.logger.status_channel;
    const std::string url = common::withReceiveBuffer(opts.lcm_url, cfg.logger.recv_buf_size);

    common::Bus bus(url);
    sizeReceiveBuffer(url, cfg.logger.recv_buf_size);
    logger::LogWriter writer(wo);
    // Per-channel statistics for the first logger::kMaxChannels channels; the others together.
    std::map<std::string, ChannelStats> stats;
    ChannelStats other;
    common::SeqTracker gaps;  // keyed by channel (HEARTBEAT: by channel and process), kMaxSequences at most
    common::LogThrottle gap_log;  // every gap is counted; the first 5 per key are logged, then 1 in 1000
    bool sequences_full = false;
    int64_t received = 0;
    int64_t awaited_status_seq = -1;  // our final status, once published: recorded when it comes back
    bool final_status_back = false, status_recorded = false;
    bus.subscribeRaw(regex, [&](const std::string& ch, const uint8_t* data, std::size_t size, int64_t recv) {
      ++received;
      auto it = stats.find(ch);
      if (it == stats.end() && stats.size() < logger::kMaxChannels) it = stats.emplace(ch, ChannelStats{}).first;
      const bool own = it != stats.end();
      ChannelStats& s = own ? it->second : other;
      if (!own && other.received == 0)
        spdlog::warn("more than {} channels: '{}' and every later new channel are counted together as '{}' (their "
                     "sequence gaps are not followed); every message is still recorded",
                     logger::kMaxChannels, common::printable(ch), logger::kOtherChannels);
      ++s.received;
      int64_t seq = 0;
      const logger::TypeInfo* type = logger::findType(data, size);
      if (type && logger::readSeq(data, size, &seq)) {  // seq is only known for lcmloc types
        if (ch == status_channel) {
          status_recorded = true;
          if (awaited_status_seq >= 0 && seq == awaited_status_seq && type->hash == lcmloc::logger_status_t::getHash())
            final_status_back = true;
        }
        std::string key = ch;
        if (type->hash == lcmloc::heartbeat_t::getHash()) {  // many publishers share HEARTBEAT
          lcmloc::heartbeat_t hb;
          if (hb.decode(data, 0, static_cast<int>(size)) >= 0) key = ch + "[" + hb.process + "]";
        }
        if (own && !gaps.tracks(key) && gaps.size() >= kMaxSequences) {
          if (!sequences_full)
            spdlog::warn("more than {} sequences (channels, heartbeat processes): the sequence gaps of '{}' and of "
                         "every later new one are not counted",
                         kMaxSequences, common::printable(key));
          sequences_full = true;
        } else if (own) {
          const auto gap = gaps.observe(key, seq);
          const std::string shown = gap.missing || gap.restarted || gap.ignored ? common::printable(key) : std::string();
          if (gap.ignored) {
            ++s.ignored;
            s.gaps -= gap.uncounted;
            if (gap_log.allow(key + ":ignored")) spdlog::warn("{}", gap.describeIgnored(shown));
          }
          if (gap.restarted && gap_log.allow(key + ":restart")) spdlog::warn("{}", gap.describeRestart(shown));
          if (gap) {
            s.gaps += gap.missing;
            if (gap_log.allow(key)) spdlog::warn("{} (lost upstream, not by the logger)", gap.describe(shown));
          }
        }
      }
      if (!writer.push({ch, std::vector<uint8_t>(data, data + size), recv})) ++s.dropped;
    });

    int64_t status_seq = 0;
    auto publishStatus = [&](const std::string& state) {
      if (status_channel.empty()) return;
      const auto w = writer.stats();
      lcmloc::logger_status_t m;
      m.utime = common::wallMicros();
      m.seq = status_seq++;
      m.state = state;
      m.file = w.file;
      m.files = w.files;
      m.bytes_written = w.bytes_written;
      m.received = received;
      m.written = w.written;
      m.dropped = w.dropped;
      m.write_lost = w.write_lost;
      m.gaps = gaps.gaps();
      m.flushed_events = w.flushed_events;
      m.queue_depth = w.queue_depth;
      m.queue_capacity = static_cast<int32_t>(wo.capacity);
      for (const auto& [ch, s] : channelRows(stats, other, kStatusNameBytes)) {
        m.channels.push_back(ch);
        m.channel_received.push_back(s.received);
        m.channel_dropped.push_back(s.dropped);
        m.channel_gaps.push_back(s.gaps);
      }
      m.num_channels = static_cast<int32_t>(m.channels.size());
      bus.publish(status_channel, m);
    };

    common::Heartbeat hb(bus, hb_channel, "lcmloc-logger", [&] {
      const auto w = writer.stats();
      return common::Heartbeat::Counters{{"received", received},
                                         {"written", w.written},
                                         {"dropped", w.dropped + w.write_lost},
                                         {"gaps", gaps.gaps()},
                                         {"rotate_failures", w.rotate_failures}};
    });
    spdlog::info("recording '{}' to {} (queue {} messages / {} MB; new file at {}; fsync every {} s)", regex,
                 writer.stats().file, wo.capacity, wo.queue_bytes >> 20,
                 wo.max_file_bytes > 0 || wo.max_file_seconds > 0
                     ? fmt::format("{} bytes / {} s", wo.max_file_bytes, wo.max_file_seconds)
                     : std::string("SIGHUP only"),
                 wo.flush_period);
    const auto status_period = std::chrono::duration<double>(cfg.logger.status_period);
    auto next_status = std::chrono::steady_clock::now();
    while (!common::stopRequested() && !writer.failed()) {
      if (g_hup.exchange(false)) {
        spdlog::info("SIGHUP: starting a new file");
        writer.requestRotate();
      }
      hb.tick();
      if (std::chrono::steady_clock::now() >= next_status) {
        // (still recording, into the file it has: a new one could not be opened)
        publishStatus(writer.stats().rotate_error.empty() ? "running" : "rotate_failed");
        next_status += std::chrono::duration_cast<std::chrono::steady_clock::duration>(status_period);
      }
      bus.handle(100);
    }
    const bool write_error = writer.failed();
    // Take what already arrived (for at most a second: a sender flooding the bus must not keep
    // the logger from stopping; what comes after that is not recorded, and said so).
    if (!bus.drain()) spdlog::warn("messages still arriving after 1 s of stopping: the rest are not recorded");
    hb.publish("stopping");
    awaited_status_seq = status_seq;
    publishStatus(write_error ? "write_error" : "stopping");
    // Our own last status (and heartbeat, sent before it) come back over the bus: wait for the
    // status when we record its channel (bounded), so the log ends with it. (Recorded: an earlier
    // status of ours came in; LCM's regex dialect is its own, so it is not matched here.)
    if (!status_channel.empty() && status_recorded) {
      const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
      while (!final_status_back && std::chrono::steady_clock::now() < until) bus.handle(20);
    }
    bus.drain();
    writer.close();

    const auto w = writer.stats();
    for (const auto& [ch, s] : channelRows(stats, other, SIZE_MAX)) {
      spdlog::info("  {:<24} {:>8} messages, {} sequence gaps, {} dropped{}", common::printable(ch), s.received, s.gaps,
                   s.dropped, s.ignored ? fmt::format(", {} seq(s) ignored", s.ignored) : "");
    }
    const auto files = writer.files();
    spdlog::info("recorded {} of {} messages on {} channels to {} file(s) ({} .. {}); {} sequence gaps upstream, "
                 "{} dropped by the logger, {} lost to write errors",
                 w.written, received,
                 other.received ? fmt::format("more than {}", logger::kMaxChannels) : std::to_string(stats.size()),
                 files.size(), files.empty() ? "" : files.front(), files.empty() ? "" : files.back(), gaps.gaps(),
                 w.dropped, w.write_lost);
    if (gaps.ignored())
      spdlog::warn("{} seq(s) ignored: each broke its sequence and the next message did not go on from it (a "
                   "corrupt seq, or a message out of order); not counted as gaps",
                   gaps.ignored());
    if (w.rotate_failures > 0)
      spdlog::warn("{} attempt(s) to start a new file failed{}; meanwhile everything was recorded into the file "
                   "open then (larger or longer than asked, nothing lost)",
                   w.rotate_failures, w.rotate_error.empty() ? "" : " (the last one: " + w.rotate_error + ")");
    if (w.failed) {
      spdlog::error("{}; stopped recording. {} holds {} whole events up to byte {} and stays readable",
                    w.error, w.file, w.written, w.bytes_written);
      return common::kExitRuntimeError;
    }
    return common::kExitOk;
  });
}
