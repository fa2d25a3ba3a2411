// lcmloc-log's subcommands (tools/log/main.cpp is their command line): info, to-csv and cut,
// each reading a truncated or damaged log up to (and past) the damage and saying where it is.
#include "lcmloc/logtool/log_tool.hpp"

#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <list>
#include <regex>
#include <set>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/seq_tracker.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/logio/event_file.hpp"
#include "lcmloc/logio/types.hpp"

namespace lcmloc::logtool {
namespace fs = std::filesystem;

namespace {

/// Scans the log, stopping early on SIGINT/SIGTERM and logging progress on big files.
logio::ScanSummary scan(const std::string& path, const std::function<void(const logio::RawEvent&)>& fn) {
  std::atomic<bool> stop{false};
  auto last = std::chrono::steady_clock::now();
  auto s = logio::scanLog(path, [&](const logio::RawEvent& ev) {
    fn(ev);
    if ((ev.index & 0xffff) == 0) {
      if (app::stopRequested()) stop = true;
      const auto now = std::chrono::steady_clock::now();
      if (now - last > std::chrono::seconds(2)) {
        spdlog::info("{}: {} events read, byte {}", path, ev.index, ev.offset);
        last = now;
      }
    }
  }, &stop);
  if (s.interrupted) spdlog::warn("{}: interrupted after {} events", path, s.events_read);
  return s;
}

void reportDamage(const logio::ScanSummary& s, const std::string& path, std::ostream* os) {
  for (const auto& i : s.issues) {
    const std::string line = fmt::format("DAMAGE in {} at byte {} (event {}): {}", path, i.byte_offset,
                                         i.event_index, i.what);
    spdlog::warn("{}", line);
    if (os) *os << line << "\n";
  }
}

std::string fingerprintHex(int64_t h) { return fmt::format("0x{:016x}", static_cast<uint64_t>(h)); }

std::string typeOf(const uint8_t* data, std::size_t size) {
  if (const auto* t = logger::findType(data, size)) return t->name;
  int64_t h = 0;
  if (!logger::readFingerprint(data, size, &h)) return "(shorter than a fingerprint)";
  return "unknown " + fingerprintHex(h);
}

/// Whole seconds rounded down (floor, also before 1970) and the microseconds past them.
std::string utimeText(int64_t us) {
  int64_t sec = us / 1000000, frac = us % 1000000;
  if (frac < 0) { --sec; frac += 1000000; }
  const std::time_t t = static_cast<std::time_t>(sec);
  std::tm tm{};
  char b[64];
  if (!gmtime_r(&t, &tm) || !std::strftime(b, sizeof b, "%Y-%m-%d %H:%M:%S", &tm))
    return fmt::format("{} us (not a calendar time)", us);
  return fmt::format("{}.{:06d} UTC", b, frac);
}

/// Seconds between two log times, without overflowing int64 on extreme times.
double spanSeconds(int64_t from, int64_t to) { return (static_cast<double>(to) - static_cast<double>(from)) * 1e-6; }

/// A payload too short to hold an LCM fingerprint (an empty event, say): no type can decode it.
bool noFingerprint(const logio::RawEvent& ev) {
  int64_t h = 0;
  return !logger::readFingerprint(ev.data, static_cast<std::size_t>(ev.size), &h);
}

/// The -c regexes of a subcommand: a channel is selected when one of them matches it whole. None
/// given: every channel, also one whose name holds a newline (which '.*' would not match).
class ChannelFilter {
 public:
  explicit ChannelFilter(const std::vector<std::string>& regexes) : all_(regexes.empty()) {
    std::string r;
    for (std::size_t i = 0; i < regexes.size(); ++i) r += (i ? "|" : "") + ("(" + regexes[i] + ")");
    try {
      if (!all_) re_ = std::regex(r);
    } catch (const std::regex_error& e) {
      throw app::ConfigError("--channel", "", "bad channel regex '" + r + "': " + e.what());
    }
  }
  bool operator()(const std::string& channel) const { return all_ || std::regex_match(channel, re_); }

 private:
  bool all_;
  std::regex re_;
};

// --- info -----------------------------------------------------------------------------------

struct ChannelInfo {
  int64_t count = 0, bytes = 0, undecodable = 0, gaps = 0, first = 0, last = 0;
  std::map<std::string, int64_t> types;   ///< of the events with a fingerprint
};

}  // namespace

int info(const std::string& path) {
  std::map<std::string, ChannelInfo> channels;
  bus::SeqTracker seqs;
  int64_t first = 0, last = 0, n = 0, undecodable = 0;
  std::vector<std::string> bad;  // first few undecodable events, with position
  const auto s = scan(path, [&](const logio::RawEvent& ev) {
    auto& c = channels[*ev.channel];
    if (c.count == 0) c.first = ev.utime;
    c.last = ev.utime;
    ++c.count;
    c.bytes += ev.size;
    if (n++ == 0) first = ev.utime;
    first = std::min(first, ev.utime);
    last = std::max(last, ev.utime);
    auto undecodableEvent = [&](const std::string& why) {
      ++c.undecodable;
      if (++undecodable <= 10)
        bad.push_back(fmt::format("undecodable {} event at byte {} (event {}): {} bytes, {}", app::printable(*ev.channel), ev.offset,
                                  ev.index, ev.size, why));
    };
    if (noFingerprint(ev)) return undecodableEvent("shorter than a fingerprint");  // not a type of its own
    const auto* type = logger::findType(ev.data, static_cast<std::size_t>(ev.size));
    ++c.types[typeOf(ev.data, static_cast<std::size_t>(ev.size))];
    if (!type) return;
    logger::Fields fields;
    if (!type->fields(ev.data, static_cast<std::size_t>(ev.size), &fields))
      return undecodableEvent("fingerprint of " + type->name);
    std::string key = *ev.channel;
    if (type->name == "lcmloc.heartbeat_t")  // many publishers share HEARTBEAT: one seq each
      for (const auto& f : fields)
        if (f.name == "process") key += "[" + f.value + "]";
    int64_t seq = 0;
    if (logger::readSeq(ev.data, static_cast<std::size_t>(ev.size), &seq)) {
      const auto g = seqs.observe(key, seq);
      c.gaps += g.missing - g.uncounted;  // a small jump that was a lone corrupt seq is taken back
    }
  });
  std::cout << "log:        " << path << " (" << s.file_size << " bytes)\n";
  std::cout << "events:     " << s.events_read << " on " << channels.size() << " channels"
            << (s.damaged ? fmt::format(", DAMAGED: {} bytes unreadable", s.bytes_unreadable) : "") << "\n";
  if (n > 0) {
    std::cout << "time span:  " << utimeText(first) << " .. " << utimeText(last)
              << fmt::format(" ({:.3f} s)\n", spanSeconds(first, last));
  }
  std::cout << fmt::format("{:<24} {:<28} {:>9} {:>10} {:>12} {:>9} {:>11}\n", "channel", "type", "count",
                           "rate[Hz]", "bytes", "seq_gaps", "undecodable");
  for (const auto& [name, c] : channels) {
    std::string type = c.types.empty() ? "(shorter than a fingerprint)" : c.types.begin()->first;
    if (c.types.size() > 1) type = "mixed (" + std::to_string(c.types.size()) + " types)";
    const double span = spanSeconds(c.first, c.last);
    const std::string rate = (c.count > 1 && span > 0) ? fmt::format("{:.2f}", (c.count - 1) / span) : "-";
    std::cout << fmt::format("{:<24} {:<28} {:>9} {:>10} {:>12} {:>9} {:>11}\n", app::printable(name), type, c.count, rate, c.bytes,
                             c.gaps, c.undecodable);
  }
  std::cout << fmt::format("total: {} events, {} sequence gaps, {} undecodable\n", s.events_read, seqs.gaps(),
                           undecodable);
  for (const auto& b : bad) std::cout << b << "\n";
  if (undecodable > static_cast<int64_t>(bad.size()))
    std::cout << "(" << undecodable - static_cast<int64_t>(bad.size()) << " more undecodable events)\n";
  reportDamage(s, path, &std::cout);
  return s.damaged ? app::kExitInputDamaged : app::kExitOk;
}

namespace {

// --- to-csv ---------------------------------------------------------------------------------

std::string csvCell(const logger::Field& f) {
  if (!f.is_string) return f.value;
  if (f.value.find_first_of(",\"\n\r") == std::string::npos) return f.value;
  std::string q = "\"";
  for (char c : f.value) q += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// At most this many columns per channel (log_utime aside). Real messages have tens to hundreds
/// of fields; every row of a channel is as wide as its widest message, so one message with a
/// huge array (a corrupt or hostile log) would make the CSV rows x width cells. Beyond this the
/// channel is refused rather than written.
constexpr std::size_t kMaxColumns = 10000;

/// Columns of one channel: the ordered union of every message's field names (arrays of
/// different lengths widen the table; missing cells stay empty). A new name goes right after the
/// previous field of the same message (before all others when none precedes it). Linear in the fields: the order
/// is a linked list until finish() numbers the columns.
struct Columns {
  std::vector<std::string> names;                      ///< in column order, after finish()
  std::unordered_map<std::string, std::size_t> index;  ///< name -> column, after finish()
  std::size_t widest = 0;                              ///< fields of the widest message
  std::size_t size() const { return order_.size() + names.size(); }  ///< columns so far
  void merge(const logger::Fields& fields) {
    widest = std::max(widest, fields.size());
    auto at = order_.begin();  // insert new names after the previous field of the same message
    for (const auto& f : fields) {
      if (order_.size() > kMaxColumns) return;  // too wide: refused, no need to grow further
      auto it = where_.find(f.name);
      if (it != where_.end()) { at = std::next(it->second); continue; }
      where_.emplace(f.name, order_.insert(at, f.name));
    }
  }
  void finish() {
    names.assign(order_.begin(), order_.end());
    for (std::size_t i = 0; i < names.size(); ++i) index[names[i]] = i;
    order_.clear();
    where_.clear();
  }

 private:
  std::list<std::string> order_;
  std::unordered_map<std::string, std::list<std::string>::iterator> where_;
};

}  // namespace

int toCsv(const std::string& path, const std::vector<std::string>& channel_regexes, const std::string& output) {
  const bool to_stdout = output.empty() || output == "-";
  if (!to_stdout) app::refuseOutputOverInputs("--output", output, {path}, "input log");
  const ChannelFilter selected(channel_regexes);
  std::map<std::string, Columns> columns;
  std::map<std::string, int64_t> undecodable, unknown;
  // Pass 1: which channels, which columns.
  const auto s = scan(path, [&](const logio::RawEvent& ev) {
    if (!selected(*ev.channel)) return;
    const auto* type = logger::findType(ev.data, static_cast<std::size_t>(ev.size));
    if (!type) { ++(noFingerprint(ev) ? undecodable : unknown)[*ev.channel]; return; }
    logger::Fields fields;
    if (!type->fields(ev.data, static_cast<std::size_t>(ev.size), &fields)) { ++undecodable[*ev.channel]; return; }
    columns[*ev.channel].merge(fields);
  });
  for (const auto& [ch, n] : unknown)
    spdlog::warn("{}: {} event(s) of a type this tool does not know, not exported", app::printable(ch), n);
  for (const auto& [ch, n] : undecodable) spdlog::warn("{}: {} undecodable event(s) skipped", app::printable(ch), n);
  reportDamage(s, path, nullptr);
  if (columns.empty()) {
    if (channel_regexes.empty())
      spdlog::error("no decodable events of lcmloc's types in {}", path);
    else
      spdlog::error("no decodable events on channels matching '{}' in {}", fmt::join(channel_regexes, "|"), path);
    return s.damaged ? app::kExitInputDamaged : app::kExitRuntimeError;  // (an empty file, no log: the damage is why)
  }
  for (auto& [ch, cols] : columns) {
    if (cols.size() > kMaxColumns)
      throw std::runtime_error(fmt::format(
          "{}: more than {} columns (widest message: {} fields): too wide for a CSV, nothing written; select the "
          "other channels with -c", app::printable(ch), kMaxColumns, cols.widest));
    cols.finish();
  }
  const bool to_dir = columns.size() > 1;
  if (to_dir && to_stdout)
    throw std::runtime_error(fmt::format("{} channels match: give --output DIR to get one CSV per channel",
                                         columns.size()));
  std::map<std::string, std::string> paths;  // channel -> its CSV file, with -o DIR
  std::map<std::string, std::unique_ptr<std::ofstream>> files;
  std::ostream* single = &std::cout;
  if (to_dir) {
    std::vector<std::string> channels;
    for (const auto& kv : columns) channels.push_back(kv.first);
    const auto stems = logio::uniqueStems(channels);  // ../x -> ___x, ./ODOMETRY next to ODOMETRY -> __ODOMETRY
    for (std::size_t i = 0; i < channels.size(); ++i) paths[channels[i]] = (fs::path(output) / (stems[i] + ".csv")).string();
    for (const auto& kv : paths) app::refuseOutputOverInputs("--output", kv.second, {path}, "input log");
    fs::create_directories(output);
  } else if (!to_stdout) {
    auto f = std::make_unique<std::ofstream>(output);
    if (!*f) throw std::runtime_error("cannot write '" + output + "'");
    single = f.get();
    files[columns.begin()->first] = std::move(f);
  }
  auto streamFor = [&](const std::string& ch) -> std::ostream& {
    if (!to_dir) return *single;
    auto& f = files[ch];
    if (!f) {
      const std::string& p = paths.at(ch);
      f = std::make_unique<std::ofstream>(p);
      if (!*f) throw std::runtime_error("cannot write '" + p + "'");
    }
    return *f;
  };
  for (const auto& [ch, cols] : columns) {
    auto& os = streamFor(ch);
    os << "log_utime";
    for (const auto& n : cols.names) os << "," << n;
    os << "\n";
  }
  // Pass 2: rows.
  std::map<std::string, int64_t> rows;
  std::vector<std::string> cells;
  scan(path, [&](const logio::RawEvent& ev) {
    auto it = columns.find(*ev.channel);
    if (it == columns.end()) return;
    const auto* type = logger::findType(ev.data, static_cast<std::size_t>(ev.size));
    logger::Fields fields;
    if (!type || !type->fields(ev.data, static_cast<std::size_t>(ev.size), &fields)) return;
    cells.assign(it->second.names.size(), "");
    for (const auto& f : fields) cells[it->second.index.at(f.name)] = csvCell(f);
    auto& os = streamFor(*ev.channel);
    os << ev.utime;
    for (const auto& c : cells) os << "," << c;
    os << "\n";
    ++rows[*ev.channel];
  });
  for (auto& [ch, f] : files) {
    f->flush();
    if (!*f) throw std::runtime_error("writing CSV for " + ch + " failed (disk full?)");
  }
  single->flush();
  if (!*single) throw std::runtime_error(std::string("writing CSV to ") + (to_stdout ? "stdout" : output) + " failed");
  for (const auto& [ch, n] : rows)
    spdlog::info("{}: {} rows, {} columns{}", app::printable(ch), n, columns[ch].names.size() + 1,
                 to_dir ? " -> " + paths.at(ch)
                        : (to_stdout ? "" : " -> " + output));
  return s.damaged ? app::kExitInputDamaged : app::kExitOk;
}

namespace {

// --- cut ------------------------------------------------------------------------------------


/// --from / --to [s] in microseconds, compared in integers (0.2 s is 200000 us exactly). A bound
/// beyond the int64 range of log times saturates (keeps all or none, as asked); not finite: refused.
int64_t boundMicros(const char* flag, double seconds) {
  if (!std::isfinite(seconds)) throw app::ConfigError(flag, "", fmt::format("{} is not a number of seconds", seconds));
  const double us = seconds * 1e6;
  if (us >= 9.2e18) return std::numeric_limits<int64_t>::max();
  if (us <= -9.2e18) return std::numeric_limits<int64_t>::min();
  return std::llround(us);
}

/// a - b, saturated to the int64 range (log times may be anything a writer put there).
int64_t saturatingSub(int64_t a, int64_t b) {
  int64_t d = 0;
  if (!__builtin_sub_overflow(a, b, &d)) return d;
  return b < 0 ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
}

}  // namespace

int cut(const std::string& path, const std::string& output, const CutOptions& o) {
  app::refuseOutputOverInputs("--output", output, {path}, "input log");
  std::optional<int64_t> from, to;
  if (o.from) from = boundMicros("--from", *o.from);
  if (o.to) to = boundMicros("--to", *o.to);
  if (from && to && *from > *to)
    throw app::ConfigError("--from", "", fmt::format("{} s is after --to {} s: nothing to keep", *o.from, *o.to));
  if (o.from_utime && o.to_utime && *o.from_utime > *o.to_utime)
    throw app::ConfigError("--from-utime", "", fmt::format("{} is after --to-utime {}: nothing to keep",
                                                              *o.from_utime, *o.to_utime));
  const ChannelFilter selected(o.channels);
  logger::EventFile out(output);
  std::optional<int64_t> t0;
  int64_t kept = 0, err = 0;
  const auto s = scan(path, [&](const logio::RawEvent& ev) {
    if (!t0) t0 = ev.utime;
    if (err) return;
    const int64_t rel = saturatingSub(ev.utime, *t0);  // [us]
    if (from && rel < *from) return;
    if (to && rel > *to) return;
    if (o.from_utime && ev.utime < *o.from_utime) return;
    if (o.to_utime && ev.utime > *o.to_utime) return;
    if (!selected(*ev.channel)) return;
    err = out.append(ev.utime, *ev.channel, ev.data, static_cast<std::size_t>(ev.size));
    if (!err) ++kept;
  });
  if (!err) err = out.close();
  reportDamage(s, path, nullptr);
  if (err)
    throw std::runtime_error(fmt::format("writing {} failed: {} ({} whole events kept)", output,
                                         std::strerror(static_cast<int>(err)), out.eventsWritten()));
  spdlog::info("wrote {} of {} events to {}", kept, s.events_read, output);
  if (kept == 0 && s.events_read > 0)
    spdlog::warn("no event is inside the window and on the selected channels: {} holds no events", output);
  return s.damaged ? app::kExitInputDamaged : app::kExitOk;
}

}  // namespace lcmloc::logtool
