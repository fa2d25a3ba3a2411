#include "recorder.hpp"

#include <sys/socket.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>

#include <spdlog/spdlog.h>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/logio/types.hpp"
#include "lcmloc/logger_status_t.hpp"

namespace lcmloc::logger {

namespace {

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
  if (rest.received > 0) rows.emplace_back(kOtherChannels, rest);
  return rows;
}

}  // namespace

void addLoggerFlags(CLI::App& app, LoggerFlags& f) {
  app.add_option("--output,-o", f.output,
                 "log file name pattern: strftime codes (%Y%m%d-%H%M%S) and {index} (overrides logger.output)");
  app.add_option("--channel", f.channels, "channel regex to record (repeatable; overrides logger.channels)");
  app.add_option("--max-file-mb", f.max_mb, "start a new file before one exceeds this many MB (overrides logger.max_file_bytes)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(s, v)) return s + " is not a number";
            return v == 0.0 || (v >= 1e-3 && v <= 1e9) ? "" : s + " is not 0 (off) or within [0.001, 1e9] MB";
          },
          "0 or MB in [0.001, 1e9]"));
  app.add_option("--max-file-seconds", f.max_seconds, "start a new file after this many seconds (overrides logger.max_file_seconds)")
      ->check(CLI::Range(app::kMaxFileSeconds.lo, app::kMaxFileSeconds.hi));
  app.add_option("--flush-period", f.flush_period, "fsync period in seconds (overrides logger.flush_period)")
      ->check(CLI::Range(app::kFlushPeriod.lo, app::kFlushPeriod.hi));
  app.add_flag("--overwrite", f.overwrite,
               "replace an existing log file (default: keep it and write NAME-001.lcmlog, the first free name)");
}

RecorderOptions recorderOptions(const app::SystemConfig& cfg, const LoggerFlags& f) {
  RecorderOptions ro;
  WriterOptions& wo = ro.writer;
  wo.pattern = f.output.empty() ? cfg.logger.output : f.output;
  if (std::error_code ec; std::filesystem::is_directory(wo.pattern, ec))
    throw app::ConfigError(f.output.empty() ? cfg.file : "--output", f.output.empty() ? "logger.output" : "",
                              "'" + wo.pattern + "' is a directory: give a file name in it, e.g. '" +
                                  (std::filesystem::path(wo.pattern) / "run.lcmlog").string() + "'");
  wo.capacity = static_cast<std::size_t>(cfg.logger.queue_capacity);
  wo.queue_bytes = cfg.logger.queue_bytes;
  wo.max_file_bytes = f.max_mb >= 0 ? static_cast<int64_t>(f.max_mb * 1e6) : cfg.logger.max_file_bytes;
  wo.max_file_seconds = f.max_seconds >= 0 ? f.max_seconds : cfg.logger.max_file_seconds;
  wo.flush_period = f.flush_period > 0 ? f.flush_period : cfg.logger.flush_period;
  wo.overwrite = f.overwrite;
  ro.regex = channelRegex(f.channels.empty() ? cfg.logger.channels : f.channels);
  try {
    std::regex check(ro.regex, std::regex::extended);  // LCM compiles it as a POSIX extended regex
  } catch (const std::regex_error& e) {
    throw app::ConfigError(f.channels.empty() ? cfg.file : "--channel", f.channels.empty() ? "logger.channels" : "",
                              "bad channel regex '" + ro.regex + "': " + e.what());
  }
  ro.status_channel = cfg.logger.status_channel;
  ro.status_period = cfg.logger.status_period;
  ro.heartbeat_channel = cfg.channels.heartbeat;
  return ro;
}

std::string channelRegex(const std::vector<std::string>& regexes) {
  if (regexes.empty()) return ".*";
  std::string r;
  for (std::size_t i = 0; i < regexes.size(); ++i) r += (i ? "|" : "") + ("(" + regexes[i] + ")");
  return "(" + r + ")";
}

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

Recorder::Recorder(RecorderOptions opts, bus::MessageBus& bus)
    : opts_(std::move(opts)),
      bus_(bus),
      writer_(opts_.writer),
      hb_(bus, opts_.heartbeat_channel, "lcmloc-logger", [this] { return counters(); }),
      next_status_(std::chrono::steady_clock::now()) {
  bus_.subscribeRaw(opts_.regex, [this](const std::string& ch, const uint8_t* data, std::size_t size, int64_t recv) {
    onMessage(ch, data, size, recv);
  });
  const WriterOptions& wo = opts_.writer;
  spdlog::info("recording '{}' to {} (queue {} messages / {} MB; new file at {}; fsync every {} s)", opts_.regex,
               writer_.stats().file, wo.capacity, wo.queue_bytes >> 20,
               wo.max_file_bytes > 0 || wo.max_file_seconds > 0
                   ? fmt::format("{} bytes / {} s", wo.max_file_bytes, wo.max_file_seconds)
                   : std::string("SIGHUP only"),
               wo.flush_period);
}

void Recorder::onMessage(const std::string& ch, const uint8_t* data, std::size_t size, int64_t recv) {
  ++received_;
  auto it = stats_.find(ch);
  if (it == stats_.end() && stats_.size() < kMaxChannels) it = stats_.emplace(ch, ChannelStats{}).first;
  const bool own = it != stats_.end();
  ChannelStats& s = own ? it->second : other_;
  if (!own && other_.received == 0)
    spdlog::warn("more than {} channels: '{}' and every later new channel are counted together as '{}' (their "
                 "sequence gaps are not followed); every message is still recorded",
                 kMaxChannels, app::printable(ch), kOtherChannels);
  ++s.received;
  int64_t seq = 0;
  const TypeInfo* type = findType(data, size);
  if (type && readSeq(data, size, &seq)) {  // seq is only known for lcmloc types
    if (ch == opts_.status_channel) {
      status_recorded_ = true;
      if (awaited_status_seq_ >= 0 && seq == awaited_status_seq_ && type->hash == lcmloc::logger_status_t::getHash())
        final_status_back_ = true;
    }
    std::string key = ch;
    if (type->hash == lcmloc::heartbeat_t::getHash()) {  // many publishers share HEARTBEAT
      lcmloc::heartbeat_t hb;
      if (hb.decode(data, 0, static_cast<int>(size)) >= 0) key = ch + "[" + hb.process + "]";
    }
    if (own && !gaps_.tracks(key) && gaps_.size() >= kMaxSequences) {
      if (!sequences_full_)
        spdlog::warn("more than {} sequences (channels, heartbeat processes): the sequence gaps of '{}' and of "
                     "every later new one are not counted",
                     kMaxSequences, app::printable(key));
      sequences_full_ = true;
    } else if (own) {
      const auto gap = gaps_.observe(key, seq);
      const std::string shown = gap.missing || gap.restarted || gap.ignored ? app::printable(key) : std::string();
      if (gap.ignored) {
        ++s.ignored;
        s.gaps -= gap.uncounted;
        if (gap_log_.allow(key + ":ignored")) spdlog::warn("{}", gap.describeIgnored(shown));
      }
      if (gap.restarted && gap_log_.allow(key + ":restart")) spdlog::warn("{}", gap.describeRestart(shown));
      if (gap) {
        s.gaps += gap.missing;
        if (gap_log_.allow(key)) spdlog::warn("{} (lost upstream, not by the logger)", gap.describe(shown));
      }
    }
  }
  if (!writer_.push({ch, std::vector<uint8_t>(data, data + size), recv})) ++s.dropped;
}

void Recorder::publishStatus(const std::string& state) {
  if (opts_.status_channel.empty()) return;
  const auto w = writer_.stats();
  lcmloc::logger_status_t m;
  m.utime = bus::wallMicros();
  m.seq = status_seq_++;
  m.state = state;
  m.file = w.file;
  m.files = w.files;
  m.bytes_written = w.bytes_written;
  m.received = received_;
  m.written = w.written;
  m.dropped = w.dropped;
  m.write_lost = w.write_lost;
  m.gaps = gaps_.gaps();
  m.flushed_events = w.flushed_events;
  m.queue_depth = w.queue_depth;
  m.queue_capacity = static_cast<int32_t>(opts_.writer.capacity);
  for (const auto& [ch, s] : channelRows(stats_, other_, kStatusNameBytes)) {
    m.channels.push_back(ch);
    m.channel_received.push_back(s.received);
    m.channel_dropped.push_back(s.dropped);
    m.channel_gaps.push_back(s.gaps);
  }
  m.num_channels = static_cast<int32_t>(m.channels.size());
  bus_.publish(opts_.status_channel, m);
}

app::Heartbeat::Counters Recorder::counters() const {
  const auto w = writer_.stats();
  return {{"received", received_},
          {"written", w.written},
          {"dropped", w.dropped + w.write_lost},
          {"gaps", gaps_.gaps()},
          {"rotate_failures", w.rotate_failures}};
}

std::vector<std::pair<std::string, ChannelStats>> Recorder::channels() const {
  return channelRows(stats_, other_, SIZE_MAX);
}

void Recorder::requestRotate() {
  spdlog::info("SIGHUP: starting a new file");
  writer_.requestRotate();
}

bool Recorder::step(int timeout_ms) {
  if (writer_.failed()) return false;
  hb_.tick();
  if (std::chrono::steady_clock::now() >= next_status_) {
    // (still recording, into the file it has: a new one could not be opened)
    publishStatus(writer_.stats().rotate_error.empty() ? "running" : "rotate_failed");
    next_status_ += std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(opts_.status_period));
  }
  bus_.handle(timeout_ms);
  return !writer_.failed();
}

int Recorder::finish() {
  const bool write_error = writer_.failed();
  // Take what already arrived (for at most a second: a sender flooding the bus must not keep
  // the logger from stopping; what comes after that is not recorded, and said so).
  if (!bus_.drain()) spdlog::warn("messages still arriving after 1 s of stopping: the rest are not recorded");
  hb_.publish("stopping");
  awaited_status_seq_ = status_seq_;
  publishStatus(write_error ? "write_error" : "stopping");
  // Our own last status (and heartbeat, sent before it) come back over the bus: wait for the
  // status when we record its channel (bounded), so the log ends with it. (Recorded: an earlier
  // status of ours came in; LCM's regex dialect is its own, so it is not matched here.)
  if (!opts_.status_channel.empty() && status_recorded_) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    while (!final_status_back_ && std::chrono::steady_clock::now() < until) bus_.handle(20);
  }
  bus_.drain();
  writer_.close();
  summary();
  return writer_.failed() ? app::kExitRuntimeError : app::kExitOk;
}

void Recorder::summary() const {
  const auto w = writer_.stats();
  for (const auto& [ch, s] : channels()) {
    spdlog::info("  {:<24} {:>8} messages, {} sequence gaps, {} dropped{}", app::printable(ch), s.received, s.gaps,
                 s.dropped, s.ignored ? fmt::format(", {} seq(s) ignored", s.ignored) : "");
  }
  const auto files = writer_.files();
  spdlog::info("recorded {} of {} messages on {} channels to {} file(s) ({} .. {}); {} sequence gaps upstream, "
               "{} dropped by the logger, {} lost to write errors",
               w.written, received_,
               other_.received ? fmt::format("more than {}", kMaxChannels) : std::to_string(stats_.size()),
               files.size(), files.empty() ? "" : files.front(), files.empty() ? "" : files.back(), gaps_.gaps(),
               w.dropped, w.write_lost);
  if (gaps_.ignored())
    spdlog::warn("{} seq(s) ignored: each broke its sequence and the next message did not go on from it (a "
                 "corrupt seq, or a message out of order); not counted as gaps",
                 gaps_.ignored());
  if (w.rotate_failures > 0)
    spdlog::warn("{} attempt(s) to start a new file failed{}; meanwhile everything was recorded into the file "
                 "open then (larger or longer than asked, nothing lost)",
                 w.rotate_failures, w.rotate_error.empty() ? "" : " (the last one: " + w.rotate_error + ")");
  if (w.failed)
    spdlog::error("{}; stopped recording. {} holds {} whole events up to byte {} and stays readable", w.error, w.file,
                  w.written, w.bytes_written);
}

}  // namespace lcmloc::logger
