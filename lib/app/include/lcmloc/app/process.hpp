#pragma once
// What every lcmloc process shares: the command line (--config, --lcm-url, --log-level),
// spdlog set-up, SIGINT/SIGTERM -> stop flag, the HEARTBEAT publisher and a pacer that runs
// simulated time against wall time with a real-time factor.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "lcmloc/bus/transport.hpp"

namespace lcmloc::common {

/// Exit codes shared by every executable (runProcess states them in every --help):
///  0 ok; 1 a runtime error; 2 a usage or configuration error: a bad command line, a bad config
///  file, a missing input file, an output that exists without --overwrite; 3 damaged input: a
///  tool that reads an LCM log did its work, but the log was truncated or had corrupt events: it
///  read up to and past the damage and reported each damaged place (the result lacks what was
///  there). A program's own codes (lcmloc-ctl's) come after these.
enum ExitCode : int {
  kExitOk = 0,
  kExitRuntimeError = 1,
  kExitUsageError = 2,
  kExitConfigError = kExitUsageError,
  kExitInputDamaged = 3
};
/// The footer runProcess adds to every program's --help.
extern const char* const kExitCodesHelp;

/// The project's version (CMake's project(VERSION)), which --version prints after the program's name.
std::string version();

/// A usage error found after parsing: runProcess exits 2 with its message.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CommonOptions {
  std::string config;     ///< scenario/system YAML file
  std::string lcm_url;    ///< LCM provider URL
  std::string log_level = "info";
};

/// The directory of the shipped configuration files: $LCMLOC_CONFIG_DIR when set, else
/// <prefix>/share/lcmloc/config, <prefix> being the directory above the running program's
/// (an installed P/bin/lcmloc-fusion reads P/share/lcmloc/config; in the build tree
/// build/share/lcmloc/config links to the source's config/). No source path is compiled in.
std::string configDir();
/// The default scenario file: configDir()/paper.yaml.
std::string defaultConfigPath();

/// Adds --config, --lcm-url, --log-level to app, with defaults filled into opts.
void addCommonOptions(CLI::App& app, CommonOptions& opts);
/// The offline tools' version (they read and write files only): --config with the tool's own
/// meaning and no default (opts.config stays empty unless given), --lcm-url accepted for
/// uniformity with the processes on the bus and unused, --log-level. Returns the --config option.
CLI::Option* addOfflineOptions(CLI::App& app, CommonOptions& opts, const std::string& config_help);

/// Sets the default spdlog logger (stderr, "[name] " prefix) at level ("trace".."off").
void setupLogging(const std::string& process_name, const std::string& level);

/// Installs SIGINT/SIGTERM handlers (no SA_RESTART, so a blocking handleTimeout returns early).
void installSignalHandlers();
bool stopRequested();
/// The flag behind stopRequested(), for readers that poll an atomic.
const std::atomic<bool>& stopFlag();
void requestStop();
/// Signal number that requested the stop (0 if none).
int stopSignal();

/// Validators for numeric options with a short message (CLI11's PositiveNumber and
/// NonNegativeNumber print the whole range of a double, 300 digits). NaN and Inf are refused
/// for every floating-point option by runProcess.
CLI::Validator positive();     ///< > 0
CLI::Validator nonNegative();  ///< >= 0
/// A wall-clock duration [s] in [0, 86400]: a day at most (1e300 s overflowed the clock's
/// deadline arithmetic). Combine with positive() where 0 is not allowed.
CLI::Validator wallSeconds();
CLI::Validator seed();         ///< an unsigned 64-bit integer, without a sign ("-1" is not 2^64 - 1)

/// What stops path from being read as a file of at most max_bytes ("" when nothing): it does not
/// exist ("no such file"), "is a directory", "is not a regular file" (a device or a FIFO:
/// /dev/zero would be read until memory runs out) or is "larger than N MB".
std::string fileProblem(const std::string& path, std::uintmax_t max_bytes = UINTMAX_MAX);
inline constexpr const char* kNoSuchFile = "no such file";
/// Throws UsageError (exit 2) naming what ("input log", "--odometry") when path is not a file
/// that can be read (fileProblem): a missing input is a usage error.
void requireInputFile(const std::string& path, const std::string& what);

/// -o,--output: where the program writes (a file, or a directory where it writes several).
CLI::Option* addOutputOption(CLI::App& app, std::string& path, const std::string& help);
/// --overwrite: replace an existing output (without it, refuseExistingOutput refuses it).
CLI::Option* addOverwriteFlag(CLI::App& app, bool& overwrite);
/// Throws UsageError (exit 2) when path exists (a regular file, or a directory that is not
/// empty) and overwrite is false, naming flag: no program replaces an output without
/// --overwrite. A device or a FIFO (/dev/null) is written to, not replaced: accepted.
void refuseExistingOutput(const std::string& path, bool overwrite, const std::string& flag = "--output");

/// Creates the output directory dir (and its parents) and checks that a file can be written in
/// it: a long experiment finds a bad --output before it computes, not after. Throws
/// std::runtime_error naming dir and the reason. With overwrite false, a directory that exists
/// and is not empty is refused first (refuseExistingOutput).
void prepareOutputDir(const std::string& dir, bool overwrite);

/// Parses the command line and runs body(), turning exceptions into one clear error line and
/// an exit code (ConfigError, UsageError -> 2, anything else -> 1). A bad command line exits 2
/// with CLI11's message. Adds --version (prints "process_name version()", exit 0) and the exit
/// codes as a footer of --help (exit 0) to app and its subcommands. Returns the exit code.
int runProcess(CLI::App& app, int argc, char** argv, const CommonOptions& opts,
               const std::string& process_name, const std::function<int()>& body);

/// Publishes heartbeat_t on the heartbeat channel once per wall second (and at the first tick).
class Heartbeat {
 public:
  using Counters = std::vector<std::pair<std::string, int64_t>>;
  /// [s] between two heartbeats (lcmloc-launcher's heartbeat_timeout is at least twice this).
  static constexpr double kPeriodSeconds = 1.0;
  Heartbeat(MessageBus& bus, std::string channel, std::string process,
            std::function<Counters()> counters = nullptr);
  /// Publishes if a second of wall time has passed since the last heartbeat (or none was sent).
  void tick();
  /// Publishes now with the given state ("starting", "running", "stopping").
  void publish(const std::string& state);
 private:
  MessageBus& bus_;
  std::string channel_, process_;
  std::function<Counters()> counters_;
  int64_t seq_ = 0;
  std::chrono::steady_clock::time_point last_{};
  bool sent_ = false;
};

/// Paces simulated time against wall time: sim time t is due at wall start + (t - t0) / factor.
/// factor <= 0 means as fast as possible.
class Pacer {
 public:
  explicit Pacer(double realtime_factor);
  /// Blocks until sim_utime is due, calling idle() at least every 100 ms while waiting.
  /// Returns false when a stop was requested meanwhile.
  bool waitUntil(int64_t sim_utime, const std::function<void()>& idle = nullptr);
 private:
  double factor_;
  bool started_ = false;
  int64_t t0_ = 0;
  std::chrono::steady_clock::time_point wall0_;
};

/// Log throttle for problems that can repeat per message (gaps, rejected inputs): allow() is true
/// for the first 5 occurrences of each key, then for one in a thousand (the counts themselves
/// are kept elsewhere and reported whole).
class LogThrottle {
 public:
  bool allow(const std::string& key) {
    const int64_t n = ++counts_[key];
    return n <= 5 || n % 1000 == 0;
  }
 private:
  std::map<std::string, int64_t> counts_;
};

/// What one message's seq says about its channel: `missing` messages before the one with seq
/// `before_seq`, a new sequence (`restarted`), and/or a seq that was ignored (`ignored`).
struct SeqGap {
  int64_t missing = 0;
  int64_t before_seq = 0;
  /// A new sequence, confirmed by the message after it: seq went back (from last_seq to
  /// before_seq; the sender started over) or jumped ahead by more than SeqTracker::kMaxSeqGap (a
  /// counter that started from another value). What the sender did not send meanwhile cannot be
  /// counted.
  bool restarted = false;
  int64_t last_seq = 0;
  /// The message before this one broke the sequence (its seq, ignored_seq, jumped from
  /// ignored_after) and this one (seq next_seq) did not go on from it: a lone corrupt seq (or a
  /// message out of order), ignored: no gap, no restart.
  bool ignored = false;
  int64_t ignored_seq = 0, ignored_after = 0, next_seq = 0;
  /// Messages counted as missing at the ignored seq and taken back now (SeqTracker::gaps() went
  /// down by as many, and up by `missing`): it was a small jump ahead, counted at once, and this
  /// message falls inside it.
  int64_t uncounted = 0;
  explicit operator bool() const { return missing > 0; }
  /// "KEY: N message(s) missing before seq S"
  std::string describe(const std::string& key) const;
  /// "KEY: seq went back from L to S (the sender started over?): ..." (or "jumped ahead")
  std::string describeRestart(const std::string& key) const;
  /// "KEY: seq I (after L) ignored: the next message (seq N) did not go on from it (a corrupt seq?)"
  std::string describeIgnored(const std::string& key) const;
};

/// Per-channel sequence-gap counter that counts lost messages, not corruption:
///  - seq = last + 1 + n with n <= kMaxUnconfirmedGap: n messages missing, counted at once (and
///    taken back, `uncounted`, when the next message falls inside the jump: 100, 108, 101);
///  - a larger jump ahead, or any step back, is taken only when the next message goes on from it
///    (its seq is the jumped one + 1): then a jump of up to kMaxSeqGap counts its missing
///    messages, and a step back or a larger jump is a new sequence (`restarted`, nothing counted);
///    otherwise the lone seq is ignored (`ignored`, counted by ignored()) and the sequence goes on
///    from the last seq taken, the ignored message standing for one of the numbers in between.
///    One corrupt seq thus costs nothing, wherever its bits flipped;
///  - a duplicate (seq = last) counts nothing.
/// A big loss at the very end of a stream (no message after the jump) is not counted.
class SeqTracker {
 public:
  static constexpr int64_t kMaxUnconfirmedGap = 1000;
  static constexpr int64_t kMaxSeqGap = int64_t{1} << 24;  ///< 16.8 million: 46 h of a 100 Hz channel
  /// The messages missing before this one (missing = 0 in order).
  SeqGap observe(const std::string& key, int64_t seq);
  /// observe() of the usual message, inline: true when seq follows on the key observed last (the
  /// message is taken, nothing to report); false, nothing changed, otherwise: observe() it then.
  bool follows(const std::string& key, int64_t seq) {
    return last_ < entries_.size() && entries_[last_].first == key && followsLast(seq);
  }
  /// follows() for a caller that knows the key is the one observed last (the one of its
  /// previous observe() or follows()): no comparison of the key.
  bool followsLast(int64_t seq) {
    if (last_ >= entries_.size()) return false;
    Entry& e = entries_[last_].second;
    if (e.pending || e.last == INT64_MAX || seq != e.last + 1) return false;
    e.jump_missing = 0;  // (as observe() takes it)
    e.last = seq;
    return true;
  }
  int64_t gaps() const { return total_; }
  int64_t gaps(const std::string& key) const;
  /// Seqs ignored as lone outliers (SeqGap::ignored).
  int64_t ignored() const { return ignored_; }
  int64_t ignored(const std::string& key) const;
  /// Keys seen (a caller that must bound its memory stops giving new keys at some size()).
  std::size_t size() const { return entries_.size(); }
  bool tracks(const std::string& key) const { return index_.count(key) > 0; }
 private:
  struct Entry {
    int64_t last = 0, gaps = 0, ignored = 0;
    bool pending = false;  ///< `candidate` broke the sequence: waiting for the next message
    int64_t candidate = 0;
    int64_t jump_missing = 0, before_jump = 0;  ///< the last seq was a small jump, counted at once
  };
  std::vector<std::pair<std::string, Entry>> entries_;
  std::unordered_map<std::string, std::size_t> index_;
  std::size_t last_ = 0;  ///< entry of the last key observed
  int64_t total_ = 0, ignored_ = 0;
};

}  // namespace lcmloc::common
