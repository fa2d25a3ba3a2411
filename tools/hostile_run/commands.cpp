#include "commands.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace lcmloc::hostile {
namespace {

nlohmann::json runJson(const LiveRunResult& r) {
  nlohmann::json j{{"figures_from", r.from_log ? "the logger's log" : "the watcher"},
                   {"poses", r.poses},
                   {"non_finite_poses", r.non_finite},
                   {"scored", r.scored},
                   {"rmse_m", r.rmse},
                   {"max_error_m", r.max_error},
                   {"pose_period_s", r.pose_period_s},
                   {"longest_pose_step_message_time_s", r.max_gap_msg_s},
                   {"pose_steps_over_2_periods", r.gaps_over},
                   {"longest_pose_silence_wall_s", r.max_silence_wall_s},
                   {"pose_silences_over_2_periods_wall", r.silences_over},
                   {"disturbing_messages_sent", r.sent},
                   {"sent_per_channel", r.sent_per_channel},
                   {"daemon_processes", r.daemon_pids},
                   {"launcher_exit", r.launcher_exit},
                   {"wall_s", r.wall_s},
                   {"last_status", r.last_status}};
  return j;
}

std::string text(const std::string& name, const LiveRunResult& r) {
  return fmt::format(
      "{}: {} POSE ({} not finite), RMSE {:.3f} m, max {:.3f} m; longest POSE step {:.3f} s of message time "
      "({} over 2 x {:.3f} s); longest silence {:.3f} s wall ({} over 2 periods); {} messages sent by the "
      "disturber; daemon processes {}; {:.0f} s wall\n",
      name, r.poses, r.non_finite, r.rmse, r.max_error, r.max_gap_msg_s, r.gaps_over, r.pose_period_s,
      r.max_silence_wall_s, r.silences_over, r.sent, r.daemon_pids, r.wall_s);
}

struct Verdict {
  nlohmann::json checks = nlohmann::json::array();
  bool ok = true;
  void check(const std::string& what, bool pass, const std::string& figures) {
    checks.push_back({{"check", what}, {"pass", pass}, {"figures", figures}});
    ok = ok && pass;
    std::cout << (pass ? "PASS " : "FAIL ") << what << ": " << figures << "\n";
  }
};

std::string reportPath(const CommandOptions& c) {
  return c.report.empty() ? c.run.out_dir + "/report.json" : c.report;
}

void write(const std::string& path, const nlohmann::json& j) {
  std::ofstream f(path);
  f << j.dump(2) << "\n";
  if (!f) throw std::runtime_error("cannot write " + path);
  std::cout << "report: " << path << "\n";
}

}  // namespace

double rssSlopeKbPerMin(const std::vector<std::pair<double, int64_t>>& samples, double from_s) {
  double n = 0, st = 0, sk = 0, stt = 0, stk = 0;
  for (const auto& [t, kb] : samples) {
    if (t < from_s) continue;
    n += 1;
    st += t;
    sk += static_cast<double>(kb);
    stt += t * t;
    stk += t * static_cast<double>(kb);
  }
  const double den = n * stt - st * st;
  return n < 2 || den <= 0 ? 0.0 : 60.0 * (n * stk - st * sk) / den;
}

int hostileCommand(const CommandOptions& c) {
  LiveRunOptions clean = c.run, hostile = c.run;
  clean.out_dir = c.run.out_dir + "/clean";
  clean.disturbance = Disturbance::kNone;
  hostile.out_dir = c.run.out_dir + "/hostile";
  hostile.disturbance = Disturbance::kHostile;
  std::cout << "clean run (" << clean.out_dir << ")\n" << std::flush;
  const LiveRunResult a = runLive(clean);
  std::cout << text("clean", a) << "hostile run (" << hostile.out_dir << ")\n" << std::flush;
  const LiveRunResult b = runLive(hostile);
  std::cout << text("hostile", b);

  Verdict v;
  v.check("RMSE within 2x of the clean run", std::isfinite(b.rmse) && b.rmse <= 2 * a.rmse,
          fmt::format("{:.3f} m against {:.3f} m", b.rmse, a.rmse));
  v.check("no POSE is NaN or Inf", b.non_finite == 0, fmt::format("{} of {}", b.non_finite, b.poses));
  v.check("POSE never silent for more than twice its period (message time)", b.gaps_over == 0,
          fmt::format("longest step {:.3f} s, period {:.3f} s", b.max_gap_msg_s, b.pose_period_s));
  v.check("the daemon never restarted", b.daemon_pids == 1, fmt::format("{} processes", b.daemon_pids));
  nlohmann::json named = nlohmann::json::object();
  for (const auto& ch : b.live_channels) {
    const auto it = b.second_publisher.find(ch);
    named[ch] = it == b.second_publisher.end() ? nlohmann::json(nullptr) : nlohmann::json(it->second);
    v.check("the status names the other publisher on " + ch, it != b.second_publisher.end(),
            it == b.second_publisher.end() ? "not named" : it->second);
  }
  std::cout << fmt::format("wall time: longest POSE silence {:.3f} s hostile, {:.3f} s clean (period {:.3f} s at "
                           "factor {}; depends on the machine's load, not checked)\n",
                           b.max_silence_wall_s, a.max_silence_wall_s, b.pose_period_s, c.run.factor);
  write(reportPath(c), {{"command", "hostile"},
                        {"factor", c.run.factor},
                        {"seed", c.run.seed},
                        {"hostile_rate", c.run.hostile_rate},
                        {"clean", runJson(a)},
                        {"hostile", runJson(b)},
                        {"rmse_ratio", a.rmse > 0 ? b.rmse / a.rmse : 0.0},
                        {"second_publisher_named", named},
                        {"checks", v.checks},
                        {"pass", v.ok}});
  return v.ok ? 0 : 1;
}

int soakCommand(const CommandOptions& c) {
  LiveRunOptions o = c.run;
  o.disturbance = Disturbance::kCorrupt;
  std::cout << fmt::format("soak: {:.0f} s, {:.2f} % of the input messages corrupted (seed {}), in {}\n",
                           o.duration_s, 100 * o.corrupt_fraction, o.seed, o.out_dir)
            << std::flush;
  const LiveRunResult r = runLive(o);
  std::cout << text("soak", r);
  int64_t first = 0, last = 0, max = 0;
  if (!r.rss_kb.empty()) {
    first = r.rss_kb.front().second;
    last = r.rss_kb.back().second;
    for (const auto& s : r.rss_kb) max = std::max(max, s.second);
  }
  const double warm = std::min(10.0, 0.2 * o.duration_s);
  const double slope = rssSlopeKbPerMin(r.rss_kb, warm);
  std::cout << fmt::format("daemon RSS: first {} kB, last {} kB, max {} kB, slope {:.1f} kB/min after {:.0f} s "
                           "({} samples)\n",
                           first, last, max, slope, warm, r.rss_kb.size());
  Verdict v;
  v.check("no POSE is NaN or Inf", r.non_finite == 0, fmt::format("{} of {}", r.non_finite, r.poses));
  v.check("no POSE step longer than twice its period (message time)", r.gaps_over == 0,
          fmt::format("longest {:.3f} s, period {:.3f} s", r.max_gap_msg_s, r.pose_period_s));
  v.check("the daemon never restarted", r.daemon_pids == 1, fmt::format("{} processes", r.daemon_pids));
  nlohmann::json rss = nlohmann::json::array();
  for (const auto& [t, kb] : r.rss_kb) rss.push_back({t, kb});
  write(reportPath(c), {{"command", "soak"},
                        {"duration_s", o.duration_s},
                        {"corrupt_fraction", o.corrupt_fraction},
                        {"seed", o.seed},
                        {"factor", o.factor},
                        {"run", runJson(r)},
                        {"rss_kb", {{"first", first}, {"last", last}, {"max", max}, {"slope_kb_per_min", slope},
                                    {"slope_from_s", warm}, {"samples", rss}}},
                        {"checks", v.checks},
                        {"pass", v.ok}});
  return v.ok ? 0 : 1;
}

}  // namespace lcmloc::hostile
