#include "lcmloc/common/process.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <thread>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "lcmloc/common/config.hpp"
#include "lcmloc/core/text.hpp"
#include "lcmloc/heartbeat_t.hpp"

namespace lcmloc::common {

namespace {
void addLogLevelOption(CLI::App& app, std::string& level) {
  app.add_option("--log-level", level, "trace, debug, info, warn, error, critical, off")
      ->capture_default_str()
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
}

std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};

extern "C" void onSignal(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
}
}  // namespace

std::string defaultConfigPath() {
#ifdef LCMLOC_DEFAULT_CONFIG
  return LCMLOC_DEFAULT_CONFIG;
#else
  return "config/paper.yaml";
#endif
}

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

void setupLogging(const std::string& process_name, const std::string& level) {
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
}

bool stopRequested() { return g_stop.load(); }
const std::atomic<bool>& stopFlag() { return g_stop; }
void requestStop() { g_stop.store(true); }
int stopSignal() { return g_signal.load(); }

int runProcess(CLI::App& app, int argc, char** argv, const CommonOptions& opts,
               const std::string& process_name, const std::function<int()>& body) {
  try {
    app.parse(argc, argv);
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
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitRuntimeError;
  }
}

// ---------------------------------------------------------------------------------------------

Heartbeat::Heartbeat(Bus& bus, std::string channel, std::string process,
                     std::function<Counters()> counters)
    : bus_(bus), channel_(std::move(channel)), process_(std::move(process)),
      counters_(std::move(counters)) {}

void Heartbeat::tick() {
  const auto now = std::chrono::steady_clock::now();
  if (sent_ && now - last_ < std::chrono::seconds(1)) return;
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
  const auto due = wall0_ + duration_cast<steady_clock::duration>(
                                duration<double, std::micro>((sim_utime - t0_) / factor_));
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
  auto it = last_ < entries_.size() && core::sameText(entries_[last_].first, key)
                ? entries_.begin() + static_cast<std::ptrdiff_t>(last_)
                : std::find_if(entries_.begin(), entries_.end(), [&](const auto& e) { return e.first == key; });
  if (it == entries_.end()) {
    entries_.push_back({key, Entry{seq}});
    last_ = entries_.size() - 1;
    return {};
  }
  last_ = static_cast<std::size_t>(it - entries_.begin());
  Entry& e = it->second;
  // A jump beyond kMaxSeqGap is a counter that started over (or a corrupt seq), not lost messages.
  int64_t step = 0;
  SeqGap gap;
  if (!__builtin_sub_overflow(seq, e.last, &step) && step > 1 && step - 1 <= kMaxSeqGap) {
    gap.missing = step - 1;
    e.gaps += gap.missing;
    total_ += gap.missing;
  }
  gap.before_seq = seq;
  gap.last_seq = e.last;
  gap.restarted = seq < e.last;
  e.last = seq;
  return gap;
}

std::string SeqGap::describeRestart(const std::string& key) const {
  return key + ": seq went back from " + std::to_string(last_seq) + " to " + std::to_string(before_seq) +
         " (the sender started over?): messages it did not send meanwhile are not counted";
}

std::string SeqGap::describe(const std::string& key) const {
  return key + ": " + std::to_string(missing) + " message(s) missing before seq " + std::to_string(before_seq);
}

int64_t SeqTracker::gaps(const std::string& key) const {
  for (const auto& e : entries_)
    if (e.first == key) return e.second.gaps;
  return 0;
}

}  // namespace lcmloc::common
