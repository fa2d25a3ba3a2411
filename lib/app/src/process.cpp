#include "lcmloc/app/process.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <thread>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/heartbeat_t.hpp"

namespace lcmloc::common {

namespace {
void addLogLevelOption(CLI::App& app, std::string& level) {
  app.add_option("--log-level", level, "trace, debug, info, warn, error, critical, off")
      ->capture_default_str()
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
}

/// CLI11 checks ranges, but "nan" passes every range check (each comparison with it is false)
/// and "inf" an open one, and an integer beyond its type is clamped: refuses both, for every
/// numeric option of app and its subcommands, naming the option.
void checkNumbers(const CLI::App& app) {
  for (const CLI::Option* o : app.get_options()) {
    const std::string type = o->get_type_name();
    const bool is_float = type.rfind("FLOAT", 0) == 0, is_int = type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0;
    if (!is_float && !is_int) continue;
    for (const std::string& token : o->results()) {  // (split at an option's delimiter already)
      if (token.empty()) continue;
      errno = 0;
      char* end = nullptr;
      if (is_float) {
        const double v = std::strtod(token.c_str(), &end);
        if (end != token.c_str() && !std::isfinite(v))
          throw CLI::ValidationError(o->get_name(), token + " is not a finite number");
      } else {
        if (token[0] == '-')
          (void)std::strtoll(token.c_str(), &end, 10);
        else
          (void)std::strtoull(token.c_str(), &end, 10);
        if (end != token.c_str() && errno == ERANGE)
          throw CLI::ValidationError(o->get_name(), token + " is out of range for an integer");
      }
    }
  }
  for (const CLI::App* sub : app.get_subcommands()) checkNumbers(*sub);
}

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};

extern "C" void onSignal(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
}
}  // namespace

std::string configDir() {
  if (const char* env = std::getenv("LCMLOC_CONFIG_DIR"); env && *env) return env;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "config";
  // <prefix>/bin/<program> -> <prefix>/share/lcmloc/config (build/share/lcmloc/config in the build tree)
  return (exe.parent_path().parent_path() / "share" / "lcmloc" / "config").string();
}

std::string defaultConfigPath() { return configDir() + "/paper.yaml"; }

void addCommonOptions(CLI::App& app, CommonOptions& opts) {
  if (opts.config.empty()) opts.config = defaultConfigPath();
  if (opts.lcm_url.empty()) opts.lcm_url = defaultLcmUrl();
  app.add_option("--config", opts.config, "scenario YAML file")->capture_default_str();
  app.add_option("--lcm-url", opts.lcm_url, "LCM provider URL (default: $LCM_DEFAULT_URL or udpm)")
      ->capture_default_str();
  addLogLevelOption(app, opts.log_level);
}

CLI::Option* addOfflineOptions(CLI::App& app, CommonOptions& opts, const std::string& config_help) {
  CLI::Option* config = app.add_option("--config", opts.config, config_help);
  app.add_option("--lcm-url", opts.lcm_url,
                 "accepted for uniformity with the processes on the bus; unused (files only, no LCM networking)");
  addLogLevelOption(app, opts.log_level);
  return config;
}

namespace {
CLI::Validator bound(const char* name, bool (*ok)(double), const char* what) {
  return CLI::Validator(
      [ok, what](std::string& s) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(s, v)) return s + " is not a number";
        return ok(v) ? std::string() : s + " is not " + what;
      },
      name);
}
}  // namespace
CLI::Validator positive() { return bound("POSITIVE", [](double v) { return v > 0.0; }, "> 0"); }
CLI::Validator nonNegative() { return bound("NONNEGATIVE", [](double v) { return v >= 0.0; }, ">= 0"); }
CLI::Validator wallSeconds() {
  return bound("SECONDS", [](double v) { return v >= 0.0 && v <= 86400.0; }, "in [0, 86400] (a day at most)");
}
CLI::Validator seed() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        uint64_t v = 0;
        // strtoull (and so a uint64_t option) takes "-1" as 2^64 - 1
        if (s.empty() || s[0] == '-' || s[0] == '+' || !CLI::detail::lexical_cast(s, v))
          return s + " is not a seed (an integer from 0 to 18446744073709551615)";
        return std::string();
      },
      "SEED");
}

std::string fileProblem(const std::string& path, std::uintmax_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return kNoSuchFile;
  if (fs::is_directory(st)) return "is a directory";
  if (!fs::is_regular_file(st)) return "is not a regular file";
  if (fs::file_size(path, ec) > max_bytes) return "larger than " + std::to_string(max_bytes >> 20) + " MB";
  return "";
}

void requireInputFile(const std::string& path, const std::string& what) {
  if (const std::string problem = fileProblem(path); !problem.empty())
    throw UsageError(what + " '" + path + "': " + (problem == kNoSuchFile ? "no such file" : "it " + problem));
}

const char* const kExitCodesHelp =
    "Exit status: 0 ok, 1 runtime error, 2 usage or configuration error (also a missing input file, or an "
    "existing output without --overwrite), 3 damaged input (the work is done with its intact part).";

std::string version() { return LCMLOC_VERSION; }

CLI::Option* addOutputOption(CLI::App& app, std::string& path, const std::string& help) {
  return app.add_option("-o,--output", path, help);
}

CLI::Option* addOverwriteFlag(CLI::App& app, bool& overwrite) {
  return app.add_flag("--overwrite", overwrite,
                      "replace an existing output (a file, or the files in a directory that is not empty); "
                      "without it an existing output is refused (exit 2)");
}

void refuseExistingOutput(const std::string& path, bool overwrite, const std::string& flag) {
  namespace fs = std::filesystem;
  if (overwrite || path.empty()) return;
  std::error_code ec;
  const auto st = fs::status(path, ec);  // (a link: what it points to)
  if (ec || !fs::exists(st)) return;
  if (fs::is_directory(st)) {
    if (fs::directory_iterator(path, ec) == fs::directory_iterator() && !ec) return;  // empty: nothing to replace
    throw UsageError(flag + " '" + path + "' is a directory that is not empty: give --overwrite to replace the "
                     "files in it, or another " + flag);
  }
  if (!fs::is_regular_file(st)) return;  // a device or a FIFO (/dev/null, /dev/stdout): written to, not replaced
  throw UsageError(flag + " '" + path + "' exists: give --overwrite to replace it, or another " + flag);
}

void prepareOutputDir(const std::string& dir, bool overwrite) {
  namespace fs = std::filesystem;
  refuseExistingOutput(dir, overwrite);
  const fs::path d = dir.empty() ? fs::path(".") : fs::path(dir);
  std::error_code ec;
  fs::create_directories(d, ec);
  if (ec) throw std::runtime_error("output directory '" + dir + "': " + ec.message());
  const fs::path probe = d / (".lcmloc_probe_" + std::to_string(::getpid()));
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) throw std::runtime_error("output directory '" + dir + "' is not writable: " + std::strerror(errno));
  std::fclose(f);
  fs::remove(probe, ec);
}

void setupLogging(const std::string& process_name, const std::string& level) {
  spdlog::drop(process_name);  // (set up again: a test that runs several programs' runProcess)
  auto logger = spdlog::stderr_color_mt(process_name);
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%H:%M:%S.%e [%n] %^%l%$: %v");
  spdlog::set_level(spdlog::level::from_str(level));
  spdlog::flush_on(spdlog::level::info);
}

void installSignalHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: blocking calls return EINTR so loops see the flag
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  // A file-size limit (ulimit -f) makes write(2) fail with EFBIG, which every writer reports,
  // instead of killing the process in the middle of an event.
  std::signal(SIGXFSZ, SIG_IGN);
}

bool stopRequested() { return g_stop.load(); }
const std::atomic<bool>& stopFlag() { return g_stop; }
void requestStop() { g_stop.store(true); }
int stopSignal() { return g_signal.load(); }

namespace {
void addExitCodesFooter(CLI::App& app) {
  const std::string own = app.get_footer();
  app.footer(own.empty() ? std::string(kExitCodesHelp) : own + "\n" + kExitCodesHelp);
  for (CLI::App* sub : app.get_subcommands({})) addExitCodesFooter(*sub);
}
}  // namespace

int runProcess(CLI::App& app, int argc, char** argv, const CommonOptions& opts,
               const std::string& process_name, const std::function<int()>& body) {
  app.set_version_flag("--version", process_name + " " + version(), "print the program's name and version, and exit");
  addExitCodesFooter(app);
  try {
    app.parse(argc, argv);
    checkNumbers(app);
  } catch (const CLI::ParseError& e) {
    // --help / --version exit 0; any other command-line error is a configuration error
    // (exit 2, as a bad config file), with CLI11's message.
    return app.exit(e) == 0 ? kExitOk : kExitConfigError;
  }
  setupLogging(process_name, opts.log_level);
  installSignalHandlers();
  try {
    return body();
  } catch (const ConfigError& e) {
    spdlog::error("configuration error: {}", e.what());
    return kExitConfigError;
  } catch (const UsageError& e) {
    spdlog::error("{}", e.what());
    return kExitUsageError;
  } catch (const CLI::Error& e) {  // an argument found bad after parsing (e.g. lcmloc-ctl's --param)
    spdlog::error("{}", e.what());
    return kExitConfigError;
  } catch (const std::bad_alloc&) {
    spdlog::error("out of memory: the run asks for more than this machine has (a very long duration, a huge input?)");
    return kExitRuntimeError;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitRuntimeError;
  }
}

// ---------------------------------------------------------------------------------------------

Heartbeat::Heartbeat(MessageBus& bus, std::string channel, std::string process,
                     std::function<Counters()> counters)
    : bus_(bus), channel_(std::move(channel)), process_(std::move(process)),
      counters_(std::move(counters)) {}

void Heartbeat::tick() {
  const auto now = std::chrono::steady_clock::now();
  if (sent_ && now - last_ < std::chrono::duration<double>(kPeriodSeconds)) return;
  publish(stopRequested() ? "stopping" : "running");
}

void Heartbeat::publish(const std::string& state) {
  lcmloc::heartbeat_t m;
  m.utime = wallMicros();
  m.seq = seq_++;
  m.process = process_;
  m.pid = static_cast<int32_t>(::getpid());
  m.state = state;
  if (counters_) {
    for (const auto& [name, value] : counters_()) {
      m.counter_names.push_back(name);
      m.counters.push_back(value);
    }
  }
  m.num_counters = static_cast<int32_t>(m.counters.size());
  bus_.publish(channel_, m);
  last_ = std::chrono::steady_clock::now();
  sent_ = true;
}

// ---------------------------------------------------------------------------------------------

Pacer::Pacer(double realtime_factor) : factor_(realtime_factor) {}

bool Pacer::waitUntil(int64_t sim_utime, const std::function<void()>& idle) {
  using namespace std::chrono;
  if (!started_) {
    started_ = true;
    t0_ = sim_utime;
    wall0_ = steady_clock::now();
  }
  if (factor_ <= 0.0) {
    if (idle) idle();
    return !stopRequested();
  }
  // (a very small factor: the wait saturates at about 30 years instead of overflowing the clock)
  const double wait_us = std::min(static_cast<double>(sim_utime - t0_) / factor_, 1e15);
  const auto due = wall0_ + duration_cast<steady_clock::duration>(duration<double, std::micro>(wait_us));
  while (!stopRequested()) {
    if (idle) idle();
    const auto now = steady_clock::now();
    if (now >= due) return true;
    std::this_thread::sleep_for(std::min<steady_clock::duration>(due - now, milliseconds(100)));
  }
  return false;
}

// ---------------------------------------------------------------------------------------------

SeqGap SeqTracker::observe(const std::string& key, int64_t seq) {
  // Most messages come on the channel of the message before: try that entry first.
  std::size_t i = last_;
  if (!(i < entries_.size() && entries_[i].first == key)) {
    const auto found = index_.find(key);
    if (found == index_.end()) {
      index_.emplace(key, entries_.size());
      entries_.push_back({key, Entry{seq}});
      last_ = entries_.size() - 1;
      SeqGap first;
      first.before_seq = first.last_seq = seq;
      return first;
    }
    i = found->second;
  }
  last_ = i;
  Entry& e = entries_[i].second;
  SeqGap gap;
  gap.before_seq = seq;
  gap.last_seq = e.last;
  if (!e.pending && e.last != INT64_MAX && seq == e.last + 1) {  // in order: the usual case
    e.jump_missing = 0;
    e.last = seq;
    return gap;
  }
  // The seq `outlier` (after `after`) broke the sequence and this message did not go on from it.
  auto ignore = [&](int64_t outlier, int64_t after) {
    gap.ignored = true;
    gap.ignored_seq = outlier;
    gap.ignored_after = after;
    gap.next_seq = seq;
    ++e.ignored;
    ++ignored_;
  };
  if (e.jump_missing > 0) {
    const int64_t counted = e.jump_missing;
    e.jump_missing = 0;
    if (e.before_jump < seq && seq < e.last) {
      // This one falls inside the small jump before (100, 108, 101): the jumped seq was a lone
      // outlier. What it counted is taken back, and the messages between the seq before it and this
      // one counted, but for one: the outlier's own.
      e.gaps -= counted;
      total_ -= counted;
      gap.uncounted = counted;
      gap.missing = std::max<int64_t>(0, seq - e.before_jump - 2);
      e.gaps += gap.missing;
      total_ += gap.missing;
      ignore(e.last, e.before_jump);
      gap.last_seq = e.before_jump;
      e.last = seq;
      return gap;
    }
  }
  if (e.pending) {
    if (seq == e.candidate) return gap;  // the jumped message again: still waiting
    e.pending = false;
    int64_t next = 0;
    if (!__builtin_add_overflow(e.candidate, 1, &next) && seq == next) {
      // Confirmed: the sender goes on from the jumped seq.
      int64_t step = 0;
      gap.before_seq = e.candidate;
      if (!__builtin_sub_overflow(e.candidate, e.last, &step) && step > 1 && step - 1 <= kMaxSeqGap) {
        gap.missing = step - 1;
        e.gaps += gap.missing;
        total_ += gap.missing;
      } else {
        gap.restarted = true;  // went back, or jumped beyond any plausible loss: a new sequence
      }
      e.last = seq;
      return gap;
    }
    // Not confirmed: a lone outlier. The sequence goes on from the last seq taken.
    ignore(e.candidate, e.last);
  }
  int64_t step = 0;
  if (__builtin_sub_overflow(seq, e.last, &step) || step < 0 || step - 1 > kMaxUnconfirmedGap) {
    e.pending = true;  // a step back or a big jump: taken when the next message goes on from it
    e.candidate = seq;
    return gap;
  }
  if (step > 1 + gap.ignored) {
    gap.missing = step - 1 - gap.ignored;  // (a message with a seq ignored stood for one of the numbers)
    e.gaps += gap.missing;
    total_ += gap.missing;
    e.jump_missing = gap.missing;
    e.before_jump = e.last;
  }
  e.last = seq;
  return gap;
}

std::string SeqGap::describeRestart(const std::string& key) const {
  const bool back = before_seq < last_seq;
  return key + ": seq " + (back ? "went back" : "jumped ahead") + " from " + std::to_string(last_seq) + " to " +
         std::to_string(before_seq) + (back ? " (the sender started over?)" : " (a new sequence, not lost messages)") +
         ": messages it did not send meanwhile are not counted";
}

std::string SeqGap::describe(const std::string& key) const {
  return key + ": " + std::to_string(missing) + " message(s) missing before seq " + std::to_string(before_seq);
}

std::string SeqGap::describeIgnored(const std::string& key) const {
  return key + ": seq " + std::to_string(ignored_seq) + " (after " + std::to_string(ignored_after) +
         ") ignored: the next message (seq " + std::to_string(next_seq) +
         ") did not go on from it (a corrupt seq, or a message out of order); not counted as a gap" +
         (uncounted > 0 ? " (the " + std::to_string(uncounted) + " message(s) counted missing before it are taken back)"
                        : std::string());
}

int64_t SeqTracker::gaps(const std::string& key) const {
  const auto it = index_.find(key);
  return it == index_.end() ? 0 : entries_[it->second].second.gaps;
}

int64_t SeqTracker::ignored(const std::string& key) const {
  const auto it = index_.find(key);
  return it == index_.end() ? 0 : entries_[it->second].second.ignored;
}

}  // namespace lcmloc::common
