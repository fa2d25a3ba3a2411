#include "live_run.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <stdexcept>
#include <sstream>
#include <thread>
#include <unordered_set>

#include <lcm/lcm-cpp.hpp>
#include <yaml-cpp/yaml.h>

#include "lcmloc/app/child_process.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/hostile/messages.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/wire.hpp"

namespace lcmloc::hostile {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// The second publisher's seqs start here: far from any stream of the system's own.
constexpr int64_t kSeqBase = 1'000'000'000;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

/// Waits for pid until the deadline; its exit code, or -1 (still running or killed).
int waitUntil(pid_t pid, Clock::time_point deadline) {
  while (true) {
    int st = 0;
    const pid_t r = ::waitpid(pid, &st, WNOHANG);
    if (r == pid) return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    if (r < 0 || Clock::now() >= deadline) return -2;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

/// The pid of the child of parent whose command is comm, or -1.
pid_t childNamed(pid_t parent, const std::string& comm) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || !std::isdigit(static_cast<unsigned char>(name[0]))) continue;
    std::ifstream f(e.path() / "stat");
    std::string line;
    if (!std::getline(f, line)) continue;
    const auto open = line.find('('), close = line.rfind(')');
    if (open == std::string::npos || close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    char state = 0;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid == parent && line.substr(open + 1, close - open - 1) == comm.substr(0, 15)) return std::stoi(name);
  }
  return -1;
}

/// The run's scenario: the base with this run's factor, laps, map and log; returns the odometry's
/// POSE period [s].
double writeScenario(const LiveRunOptions& o, const std::string& path, const std::string& map,
                     const std::string& log) {
  YAML::Node y = YAML::LoadFile(o.scenario);
  y["scenario"]["realtime_factor"] = o.factor;
  const double scale = o.factor > 1 ? o.factor : 1.0;
  const double window = y["fusion"]["reorder_window"] ? y["fusion"]["reorder_window"].as<double>() : 0.05;
  const double jump = y["fusion"]["max_time_jump"] ? y["fusion"]["max_time_jump"].as<double>() : 1.0;
  y["fusion"]["reorder_window"] = window * scale;
  y["fusion"]["max_time_jump"] = jump * scale;
  y["fusion"]["map_file"] = fs::absolute(map).string();
  y["logger"]["output"] = fs::absolute(log).string();
  int laps = o.laps;
  if (laps <= 0) {  // enough laps for the duration, and a few metres more
    double lap = 0;
    for (const auto& s : y["path"]["segments"]) lap += s["length"].as<double>();
    const double speed = y["vehicle"] && y["vehicle"]["speed"] ? y["vehicle"]["speed"].as<double>() : 1.5;
    laps = static_cast<int>(std::ceil((o.duration_s * std::max(o.factor, 1.0) * speed + 20.0) / lap));
  }
  if (laps > 1) {
    YAML::Node segs = YAML::Clone(y["path"]["segments"]), all(YAML::NodeType::Sequence);
    double lap = 0;
    for (const auto& s : segs) lap += s["length"].as<double>();
    for (int i = 0; i < laps; ++i)
      for (const auto& s : segs) all.push_back(YAML::Clone(s));
    y["path"]["segments"] = all;
    const double spacing = y["markers"]["spacing"] ? y["markers"]["spacing"].as<double>() : 2.0;
    const double first = y["markers"]["first_at"] ? y["markers"]["first_at"].as<double>() : 2.0;
    y["markers"]["count"] = static_cast<int>((laps * lap - first - 4.0) / spacing) + 1;  // all along
  }
  std::ofstream(path) << y << "\n";
  const double rate = y["odometry"] && y["odometry"]["rate_hz"] ? y["odometry"]["rate_hz"].as<double>() : 100.0;
  const int every = y["fusion"]["output_every"] ? y["fusion"]["output_every"].as<int>() : 1;
  return every / rate;
}

/// The system's outputs as seen: by the watcher (with the time each reached its socket: the
/// kernel's receive time, so that the watcher's own work, in the process that also sends the
/// floods, does not delay what it measures) or in the logger's log.
struct Track {
  struct Pose { int64_t utime; double x, y; bool finite; int64_t recv_utime; };
  std::vector<Pose> poses;
  std::vector<eval::TruthPose> truth;
  std::map<std::string, std::string> second;  ///< channel -> the status's second_publisher (or source_replaced) words
  std::string last_status;
};

/// Takes one message of the pose, truth or status channel into t; false for any other channel.
bool take(const app::ChannelConfig& ch, const std::string& channel, const uint8_t* data, std::size_t n,
          int64_t recv_utime, Track& t) {
  const int len = static_cast<int>(n);
  if (channel == ch.pose) {
    pose_t p{};
    if (p.decode(data, 0, len) < 0 || p.state.size() < 2) return true;
    bool finite = true;
    for (double v : p.state) finite = finite && std::isfinite(v);
    t.poses.push_back({p.utime, p.state[0], p.state[1], finite, recv_utime});
  } else if (channel == ch.ground_truth) {
    ground_truth_t g{};
    if (g.decode(data, 0, len) >= 0) t.truth.push_back({g.utime, g.x, g.y, g.heading, true});
  } else if (channel == ch.status) {
    fusion_status_t s{};
    if (s.decode(data, 0, len) < 0) return true;
    const std::string on = s.detail.substr(0, s.detail.find(':'));
    if (s.event == "second_publisher" && t.second[on].rfind("second_publisher", 0) != 0)
      t.second[on] = "second_publisher: " + s.detail;
    if (s.event == "source_replaced" && t.second[on].empty()) t.second[on] = "source_replaced: " + s.detail;
    if (s.event == "periodic" || s.event == "stopped") t.last_status = s.detail;
  } else {
    return false;
  }
  return true;
}

/// What the watcher saw, filled by the receive thread.
struct Seen {
  std::mutex mu;
  Track track;
  int64_t live_utime = 0;  ///< the last odometry message's time (the live time)
  int64_t live_recv_utime = 0;  ///< when the system's last odometry message reached the watcher's socket [us, wall]
  std::set<std::string> live_channels;
};

/// POSE's count, NaN, message-time steps, and its error against the truth into r.
void score(Track& t, double period, LiveRunResult& r) {
  std::sort(t.truth.begin(), t.truth.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });
  t.second.erase("");
  double sq = 0;
  for (std::size_t i = 0; i < t.poses.size(); ++i) {
    const auto& p = t.poses[i];
    ++r.poses;
    if (!p.finite) ++r.non_finite;
    if (i > 0) {
      const double step = (p.utime - t.poses[i - 1].utime) * 1e-6;
      r.max_gap_msg_s = std::max(r.max_gap_msg_s, step);
      r.gaps_over += step > 2 * period;
    }
    const auto truth = p.finite ? eval::interpolateTruth(t.truth, p.utime, 100'000) : std::nullopt;
    if (!truth) continue;
    const double e = std::hypot(p.x - truth->x, p.y - truth->y);
    sq += e * e;
    r.max_error = std::max(r.max_error, e);
    ++r.scored;
  }
  r.rmse = r.scored ? std::sqrt(sq / static_cast<double>(r.scored)) : NAN;
  for (const auto& [ch, words] : t.second)
    if (!words.empty()) r.second_publisher[ch] = words;
  r.last_status = t.last_status;
}

/// The second publisher: each kind of bad message on every input channel, round robin, its own
/// seq streams far from the system's, times near the live time (the time kinds: their own).
class Hostile {
 public:
  Hostile(const app::ChannelConfig& ch, uint64_t seed) : ch_(ch), kinds_(kinds(ch)), rng_(seed) {
    for (const auto& fault : ch.magruler)  // (kinds() has the first ruler channel only)
      if (fault != kinds_[1].channel) kinds_.push_back({fault, kinds_[1].make});
  }
  /// Publishes the next message(s); returns how many. With second_only, nothing on a channel that
  /// the system's own drivers publish on (odometry, ruler) before its own stream was seen there.
  int sendNext(lcm::LCM& lcm, int64_t live, const std::set<std::string>& seen, bool second_only,
               std::map<std::string, int64_t>& per_channel) {
    const std::size_t n_bad = badKinds().size() + 2;  // + a wrong but decodable one, + a control command
    const std::size_t slot = next_++ % ((kinds_.size()) * n_bad);
    const Kind& kind = kinds_[slot % kinds_.size()];
    const std::size_t what = slot / kinds_.size();
    const bool driven = kind.channel == ch_.odometry ||
                        std::find(ch_.magruler.begin(), ch_.magruler.end(), kind.channel) != ch_.magruler.end();
    if (what != n_bad - 1 && second_only && driven && !seen.count(kind.channel)) return 0;
    std::uniform_int_distribution<int64_t> jitter(-20'000, 20'000);
    const int64_t t = live + jitter(rng_), s = kSeqBase + seq_[kind.channel]++;
    if (what == n_bad - 1) {
      const auto bytes = badControl(static_cast<int>(next_ / 7), s, t);
      lcm.publish(ch_.control, bytes.data(), static_cast<unsigned>(bytes.size()));
      ++per_channel[ch_.control];
      return 1;
    }
    const bool wrong = what == n_bad - 2;
    const std::string& bad = wrong ? std::string() : badKinds()[what];
    const auto bytes = wrong ? wrongMessage(kind, ch_, static_cast<int>(next_ / 3), s, t) : badMessage(kind, bad, s, t);
    const int copies = bad == "flood" ? 100 : 1;
    for (int c = 0; c < copies; ++c) lcm.publish(kind.channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    per_channel[kind.channel] += copies;
    return copies;
  }

 private:
  app::ChannelConfig ch_;
  std::vector<Kind> kinds_;
  std::mt19937_64 rng_;
  std::map<std::string, int64_t> seq_;
  std::size_t next_ = 0;
};

/// A corrupted copy of bytes: one byte flipped, the body cut, or random bytes of the same size.
std::vector<uint8_t> corrupt(const uint8_t* data, std::size_t n, std::mt19937_64& rng) {
  std::vector<uint8_t> b(data, data + n);
  if (b.empty()) return {0xff};
  std::uniform_int_distribution<std::size_t> pos(0, b.size() - 1);
  switch (rng() % 3) {
    case 0: b[pos(rng)] ^= static_cast<uint8_t>(1u << (rng() % 8)); break;
    case 1: b.resize(pos(rng)); break;
    default: for (auto& c : b) c = static_cast<uint8_t>(rng()); break;
  }
  return b;
}

}  // namespace

LiveRunResult runLive(const LiveRunOptions& o) {
  fs::create_directories(o.out_dir);
  const std::string scenario = o.out_dir + "/scenario.yaml", map = o.out_dir + "/map.csv",
                    log = o.out_dir + "/run.lcmlog";
  LiveRunResult r;
  r.pose_period_s = writeScenario(o, scenario, map, log);
  const app::SystemConfig cfg = app::loadSystemConfig(scenario);
  const pid_t sim = app::spawnWithOutput({o.bin_dir + "/lcmloc-sim", "--config", scenario, "--write-map", map, "--log-level", "warn"},
                          o.out_dir + "/write_map.out");
  if (waitUntil(sim, Clock::now() + std::chrono::seconds(60)) != 0)
    throw std::runtime_error("lcmloc-sim --write-map failed (" + o.out_dir + "/write_map.out)");

  // The watcher's socket gets a receive buffer as the system's (a POSE lost by a slow watcher would
  // read as a gap).
  const bool udpm = o.lcm_url.rfind("udpm://", 0) == 0 && o.lcm_url.find("recv_buf_size") == std::string::npos;
  const std::string watch_url =
      udpm ? o.lcm_url + (o.lcm_url.find('?') == std::string::npos ? "?" : "&") + "recv_buf_size=8388608" : o.lcm_url;
  lcm::LCM lcm(watch_url), out(o.lcm_url);
  if (!lcm.good() || !out.good()) throw std::runtime_error("cannot open LCM on " + o.lcm_url);
  Seen seen;
  std::vector<std::string> inputs{cfg.channels.odometry, cfg.channels.imu, cfg.channels.gps, cfg.channels.landmarks,
                                  cfg.channels.beacons, cfg.channels.vision, cfg.channels.control};
  for (const auto& m : cfg.channels.magruler) inputs.push_back(m);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u01(0, 1);
  std::unordered_set<std::string> ours;  // the corrupted copies sent (heard back: not corrupted again)
  std::atomic<int64_t> sent{0};
  std::map<std::string, int64_t> sent_per_channel;
  std::mutex sent_mu;
  auto onRaw = [&](const lcm::ReceiveBuffer* rb, const std::string& channel) {
    const auto* data = static_cast<const uint8_t*>(rb->data);
    const std::size_t n = rb->data_size;
    {
      std::lock_guard<std::mutex> l(seen.mu);
      if (take(cfg.channels, channel, data, n, rb->recv_utime, seen.track)) return;
    }
    {  // an input channel
      const std::string bytes(reinterpret_cast<const char*>(data), n);
      if (ours.erase(bytes)) return;
      // Every input type starts with utime and seq after its fingerprint: the system's own seqs
      // stay far below the second publisher's.
      if (n >= 24 && static_cast<int64_t>(wire::loadBig(data + 16, 8)) < kSeqBase) {
        std::lock_guard<std::mutex> l(seen.mu);
        seen.live_channels.insert(channel);
      }
      if (channel == cfg.channels.odometry) {
        odometry_t m{};
        if (m.decode(data, 0, static_cast<int>(n)) == static_cast<int>(n) && m.seq < kSeqBase) {
          std::lock_guard<std::mutex> l(seen.mu);
          seen.live_utime = std::max(seen.live_utime, m.utime);
          seen.live_recv_utime = rb->recv_utime;
        }
      }
      if (o.disturbance != Disturbance::kCorrupt) return;
      if (u01(rng) >= o.corrupt_fraction) return;
      const auto c = corrupt(data, n, rng);
      ours.insert(std::string(c.begin(), c.end()));
      out.publish(channel, c.data(), static_cast<unsigned>(c.size()));
      ++sent;
      std::lock_guard<std::mutex> l(sent_mu);
      ++sent_per_channel[channel];
    }
  };
  std::string re = "^(" + cfg.channels.pose + "|" + cfg.channels.ground_truth + "|" + cfg.channels.status;
  for (const auto& c : inputs) re += "|" + c;
  lcm.subscribeFunction(re + ")$", +[](const lcm::ReceiveBuffer* rb, const std::string& ch, decltype(onRaw)* f) {
    (*f)(rb, ch);
  }, &onRaw);
  std::atomic<bool> stop{false};
  std::thread rx([&] {
    while (!stop) lcm.handleTimeout(50);
  });

  const auto start = Clock::now();
  const pid_t launcher = app::spawnWithOutput({o.bin_dir + "/lcmloc-launcher", "--system", o.system, "--config", scenario,
                                "--lcm-url", o.lcm_url, "--log-level", "warn"},
                               o.out_dir + "/launcher.out");
  Hostile hostile(cfg.channels, o.seed);
  std::set<pid_t> daemons;
  auto next_rss = start;
  const auto deadline = o.duration_s > 0 ? start + std::chrono::duration_cast<Clock::duration>(
                                                       std::chrono::duration<double>(o.duration_s))
                                         : Clock::time_point::max();
  const auto gap = std::chrono::duration<double>(1.0 / std::max(1.0, o.hostile_rate));
  auto next_send = start;
  int st = 0;
  while (::waitpid(launcher, &st, WNOHANG) == 0) {
    const auto now = Clock::now();
    if (now >= deadline) break;
    if (now >= next_rss) {
      next_rss += std::chrono::seconds(1);
      const pid_t d = childNamed(launcher, "lcmloc-fusion");
      if (d > 0) {
        daemons.insert(d);
        if (const int64_t kb = app::procStatusKb(d, "VmRSS")) r.rss_kb.emplace_back(seconds(now - start), kb);
      }
    }
    int64_t live = 0;
    std::set<std::string> live_channels;
    {
      std::lock_guard<std::mutex> l(seen.mu);
      live = seen.live_utime;
      live_channels = seen.live_channels;
    }
    if (o.disturbance == Disturbance::kHostile && live > 0) {
      while (next_send <= now) {
        std::lock_guard<std::mutex> l(sent_mu);
        const int n = hostile.sendNext(out, live, live_channels, !o.hostile_first, sent_per_channel);
        sent += n;
        next_send += std::chrono::duration_cast<Clock::duration>(gap * n);  // (a flood: its copies count)
      }
    } else {
      next_send = now;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  r.wall_s = seconds(Clock::now() - start);
  if (Clock::now() >= deadline) {
    ::kill(launcher, SIGTERM);
    r.launcher_exit = waitUntil(launcher, Clock::now() + std::chrono::seconds(60));
    if (r.launcher_exit == -2) {
      ::kill(launcher, SIGKILL);
      ::waitpid(launcher, &st, 0);
    }
  } else {
    r.launcher_exit = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  stop = true;
  rx.join();

  std::lock_guard<std::mutex> l(seen.mu);
  if (seen.track.poses.empty()) throw std::runtime_error("no POSE from the system (" + o.out_dir + "/launcher.out)");
  // Message time, errors, the status and the wall-clock silences: from the logger's log (a
  // recorder with a large receive buffer, its timestamps the kernel's receive times), or the
  // watcher's when there is none. (The watcher shares its process with the sender of the floods,
  // and LCM's receive thread there drops datagrams under them: a POSE it lost would count as a
  // silence the system never had.)
  Track recorded;
  int64_t recorded_live = 0;  // the system's last odometry message in the log [us, receive time]
  if (fs::exists(log)) {
    logio::scanLog(log, [&](const logio::RawEvent& e) {
      take(cfg.channels, *e.channel, e.data, static_cast<std::size_t>(e.size), e.utime, recorded);
      if (*e.channel == cfg.channels.odometry) {
        odometry_t m{};
        if (m.decode(e.data, 0, static_cast<int>(e.size)) == static_cast<int>(e.size) && m.seq < kSeqBase)
          recorded_live = std::max(recorded_live, e.utime);
      }
    });
  }
  // While the system's odometry comes: the poses still in the horizon when the input ends come
  // out together, when the daemon flushes it, not on the odometry.
  const bool from_log = !recorded.poses.empty();
  const Track& timed = from_log ? recorded : seen.track;
  const int64_t live_end = from_log ? recorded_live : seen.live_recv_utime;
  for (std::size_t i = 1; i < timed.poses.size() && timed.poses[i].recv_utime <= live_end; ++i) {
    const double silence = 1e-6 * static_cast<double>(timed.poses[i].recv_utime - timed.poses[i - 1].recv_utime);
    r.max_silence_wall_s = std::max(r.max_silence_wall_s, silence);
    r.silences_over += silence > 2 * r.pose_period_s / std::max(o.factor, 1e-9);
  }
  r.from_log = !recorded.poses.empty();
  score(r.from_log ? recorded : seen.track, r.pose_period_s, r);
  r.sent = sent;
  r.sent_per_channel = sent_per_channel;
  r.live_channels = seen.live_channels;
  r.daemon_pids = static_cast<int>(daemons.size());
  return r;
}

}  // namespace lcmloc::hostile
