// lcmloc-evaluate: scores the estimates recorded in any log (POSE, optionally every POSE_*)
// against the ground truth recorded with them: position / heading / drift errors, NEES against
// its chi-square bounds, gate statistics from GATE; writes report.json, PNG figures and, on
// request, TUM trajectory files for the evo tools. Nothing is replayed (that is lcmloc-eval).
#include <chrono>
#include <filesystem>
#include <iostream>
#include <sstream>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/eval/trajectory_report.hpp"

namespace {

constexpr int kExitNothingUsable = lcmloc::common::kExitRuntimeError;
constexpr int kExitBadConfig = lcmloc::common::kExitConfigError;

std::string channelList(const std::map<std::string, int64_t>& counts) {
  if (counts.empty()) return "none";
  std::ostringstream s;
  bool first = true;
  for (const auto& [c, n] : counts) {
    s << (first ? "" : ", ") << lcmloc::eval::withoutControlCharacters(c) << " (" << n << ")";
    first = false;
  }
  return s.str();
}

std::string utimeSpan(int64_t a, int64_t b) {
  std::ostringstream s;
  s << std::fixed;
  s.precision(3);
  s << "[" << static_cast<double>(a) * 1e-6 << " s, " << static_cast<double>(b) * 1e-6 << " s]";
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace lcmloc;
  CLI::App app{"lcmloc-evaluate: scores the estimates recorded in an LCM log (pose_t) against the ground truth "
               "recorded with them: position, heading and drift errors, NEES against its chi-square bounds, gate "
               "statistics; writes report.json, PNG figures and TUM files (docs/evaluate.md). Exit: 0 done, 1 nothing "
               "to evaluate, 2 bad options or config, 3 done from a damaged log (its intact events; each damaged "
               "place reported)."};
  std::string log_path, out_dir = "out/evaluate", tum_dir;
  common::CommonOptions opts;
  const std::string& config_path = opts.config;
  eval::TrajectoryLogOptions lo;
  eval::EvaluateOptions eo;
  eval::TrajectoryPlotOptions po;
  std::vector<double> datum;
  bool no_plots = false, export_only = false;
  app.add_option("log", log_path, "LCM log file holding estimates (and ground truth)")->required();
  auto* o_pose =
      app.add_option("--pose-channel", lo.pose_channel, "channel of the estimates (pose_t)")->capture_default_str();
  app.add_flag("--all-poses", lo.all_pose_channels, "also score every other POSE_* channel (shadow filters)");
  auto* o_truth = app.add_option("--truth-channel", lo.truth_channel,
                                 "channel of the reference: ground_truth_t, or gps_fix_t (needs a datum)")
                      ->capture_default_str();
  auto* o_gate = app.add_option("--gate-channel", lo.gate_channel, "channel of the gate decisions (gate_decision_t)")
                     ->capture_default_str();
  app.add_option("--datum", datum, "LAT,LON[,ALT]: origin of the local frame for gps_fix_t truth [deg, deg, m]")
      ->delimiter(',')
      ->expected(1, 3)  // 2 or 3, checked below (a minimum above 1 would print "x 2" in --help)
      ->type_name("LAT,LON[,ALT]");
  app.add_option("-o,--out", out_dir, "output directory for report.json and figures")->capture_default_str();
  app.add_option("--tum-dir", tum_dir, "write estimate.tum (estimate_<CHANNEL>.tum for POSE_*) and truth.tum here");
  app.add_flag("--export-only", export_only, "only export TUM files (--tum-dir): no truth needed, no scoring");
  app.add_option("--segment-lengths", eo.segment_lengths, "drift segment lengths [m]")
      ->delimiter(',')->capture_default_str()->check(lcmloc::common::positive());
  app.add_option("--max-truth-gap", eo.max_truth_gap_s,
                 "estimates between truth samples further apart than this are not scored [s] (0 = no limit)")
      ->capture_default_str()->check(lcmloc::common::nonNegative());
  app.add_option("--confidence", eo.confidence, "probability of the two-sided chi-square intervals")
      ->capture_default_str()->check(CLI::Range(0.5, 0.9999));
  app.add_option("--ellipse-every", po.ellipse_every, "covariance ellipse at every k-th scored estimate (0 = about 40)")
      ->capture_default_str()->check(lcmloc::common::nonNegative());
  app.add_option("--ellipse-sigma", po.ellipse_sigma, "ellipse size in standard deviations")
      ->capture_default_str()->check(lcmloc::common::positive());
  app.add_flag("--no-plots", no_plots, "do not draw figures");
  common::addOfflineOptions(app, opts,
                            "system config (YAML): its channels.pose, channels.ground_truth, channels.gate and "
                            "datum are the defaults of --pose-channel, --truth-channel, --gate-channel and --datum");
  return common::runProcess(app, argc, argv, opts, "lcmloc-evaluate", [&] {
    if (export_only && tum_dir.empty()) {
      spdlog::error("--export-only needs --tum-dir DIR");
      return kExitBadConfig;
    }
    if (datum.size() == 1) {
      spdlog::error("--datum needs LAT,LON or LAT,LON,ALT (got one number)");
      return kExitBadConfig;
    }
    try {
      if (!config_path.empty()) {
        const auto cfg = common::loadSystemConfig(config_path);
        if (!o_pose->count()) lo.pose_channel = cfg.channels.pose;
        if (!o_truth->count()) lo.truth_channel = cfg.channels.ground_truth;
        if (!o_gate->count()) lo.gate_channel = cfg.channels.gate;
        lo.datum = cfg.datum;
      }
      if (!datum.empty()) {
        common::Datum d;
        d.latitude = datum[0];
        d.longitude = datum[1];
        d.altitude = datum.size() > 2 ? datum[2] : 0.0;
        common::LocalFrame check(d);  // throws std::invalid_argument when out of range
        lo.datum = d;
      }
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitBadConfig;
    }
    const bool truth_is_a_pose = lo.truth_channel == lo.pose_channel ||
                                 (lo.all_pose_channels && lo.truth_channel.rfind(lo.pose_channel + "_", 0) == 0);
    if (truth_is_a_pose) {
      spdlog::error("--truth-channel {} is a channel of the estimates (--pose-channel {}{}): the truth must come "
                    "from another channel",
                    lo.truth_channel, lo.pose_channel, lo.all_pose_channels ? ", --all-poses" : "");
      return kExitBadConfig;
    }

    eval::TrajectoryLog log;
    try {
      // A progress line every 2 s of wall time on long logs.
      const auto start = std::chrono::steady_clock::now();
      auto last = start;
      log = eval::readTrajectoryLog(log_path, lo, &common::stopFlag(), [&](int64_t pos, int64_t size) {
        const auto now = std::chrono::steady_clock::now();
        if (now - last < std::chrono::seconds(2)) return;
        last = now;
        spdlog::info("reading {}: {:.0f} of {:.0f} MB ({:.0f} %)", log_path, pos / 1e6, size / 1e6,
                     size > 0 ? 100.0 * static_cast<double>(pos) / static_cast<double>(size) : 100.0);
      });
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitNothingUsable;
    }
    // A channel none of whose messages is of the type it should carry: the wrong channel given.
    const std::pair<std::string, std::string> expected[] = {{"--pose-channel", lo.pose_channel},
                                                            {"--truth-channel", lo.truth_channel},
                                                            {"--gate-channel", lo.gate_channel}};
    for (const auto& [flag, ch] : expected) {
      const auto n = log.channel_counts.find(ch);
      const auto bad = log.undecodable.find(ch);
      if (n != log.channel_counts.end() && bad != log.undecodable.end() && bad->second == n->second) {
        spdlog::error("{} {}: none of its {} messages is of the type that option reads ({}): is it the right "
                      "channel?", flag, common::printable(ch), n->second,
                      flag == "--pose-channel" ? "pose_t" : flag == "--truth-channel" ? "ground_truth_t or gps_fix_t"
                                                                                      : "gate_decision_t");
        return kExitBadConfig;
      }
    }
    constexpr std::size_t kShownIssues = 10;
    for (std::size_t i = 0; i < log.issues.size() && i < kShownIssues; ++i)
      spdlog::warn("{}: {}", log_path, log.issues[i].describe());
    if (log.issues.size() > kShownIssues)
      spdlog::warn("{}: ... and {} more issue(s) (report.json lists them all)", log_path,
                   log.issues.size() - kShownIssues);
    if (log.damaged)
      spdlog::warn("{}: damaged log: {} of {} bytes unreadable; evaluating the {} intact events", log_path,
                   log.bytes_unreadable, log.file_size, log.events_read);
    if (log.interrupted) spdlog::warn("interrupted: evaluating the {} events read so far", log.events_read);

    // Tracks with estimates; the pose channel first.
    std::vector<eval::EstimateTrack> tracks;
    for (const auto& t : log.tracks)
      if (!t.poses.empty()) tracks.push_back(t);
    if (tracks.empty()) {
      spdlog::error("{}: no estimates (pose_t) on channel {}{} in {} events; channels in the log: {}", log_path,
                    lo.pose_channel, lo.all_pose_channels ? " or POSE_*" : "", log.events_read,
                    channelList(log.channel_counts));
      return kExitNothingUsable;
    }
    if (log.tracks.front().poses.empty())
      spdlog::warn("{}: no estimates on {}; scoring {}", log_path, lo.pose_channel, eval::withoutControlCharacters(tracks.front().channel));

    if (!tum_dir.empty()) {
      try {
        std::filesystem::create_directories(tum_dir);
        std::vector<std::string> channels;
        for (const auto& t : tracks) channels.push_back(t.channel);
        const auto stems = eval::uniqueStems(channels);  // a channel name is no path
        for (std::size_t i = 0; i < tracks.size(); ++i) {
          const auto& t = tracks[i];
          const std::string name = t.channel == lo.pose_channel ? "estimate" : "estimate_" + stems[i];
          const std::string file = tum_dir + "/" + name + ".tum";
          const auto n = eval::writeTum(file, t.poses);
          std::cout << "TUM: " << file << " (" << n << " poses";
          if (n != t.poses.size()) std::cout << "; " << t.poses.size() - n << " with a repeated utime left out";
          std::cout << ")\n";
        }
        if (!log.truth.empty()) {
          eval::writeTum(tum_dir + "/truth.tum", log.truth);
          std::cout << "TUM: " << tum_dir << "/truth.tum (" << log.truth.size() << " poses"
                    << (log.truth.front().has_heading ? "" : ", no heading: identity rotation") << ")\n";
        }
      } catch (const std::exception& e) {
        spdlog::error("TUM export to '{}': {}", tum_dir, e.what());
        return kExitNothingUsable;
      }
      if (export_only) return 0;
    }

    if (log.truth.empty()) {
      spdlog::error("{}: no ground truth on channel {} ({}); channels in the log: {}. Choose it with --truth-channel, "
                    "or export the estimates only with --tum-dir DIR --export-only",
                    log_path, lo.truth_channel,
                    log.channel_counts.count(lo.truth_channel) ? "present but not usable, see the warnings above"
                                                               : "not in the log",
                    channelList(log.channel_counts));
      return kExitNothingUsable;
    }

    std::vector<eval::TrackScore> scores;
    bool any_scored = false;
    for (const auto& t : tracks) {
      scores.push_back(eval::scoreTrack(t, log.truth, eo));
      const auto& s = scores.back();
      any_scored = any_scored || s.scored > 0;
      if (s.before_truth + s.after_truth + s.in_truth_gap > 0)
        spdlog::warn("{}: {} of {} estimates not scored: {} before the first truth sample, {} after the last, {} in "
                     "truth gaps longer than {} s",
                     eval::withoutControlCharacters(s.channel), s.before_truth + s.after_truth + s.in_truth_gap, s.estimates, s.before_truth,
                     s.after_truth, s.in_truth_gap, eo.max_truth_gap_s);
    }
    if (!any_scored) {
      const auto& t = tracks.front();
      spdlog::error("{}: no estimate lies inside the ground truth: estimates on {} span {}, truth on {} spans {}{}",
                    log_path, eval::withoutControlCharacters(t.channel), utimeSpan(t.poses.front().utime, t.poses.back().utime), lo.truth_channel,
                    utimeSpan(log.truth.front().utime, log.truth.back().utime),
                    eo.max_truth_gap_s > 0 ? " (gaps over --max-truth-gap excluded)" : "");
      return kExitNothingUsable;
    }
    const auto gates = eval::gateStatistics(log.gates, eo.confidence);

    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec) {
      spdlog::error("cannot create output directory '{}': {}", out_dir, ec.message());
      return kExitNothingUsable;
    }
    try {
      eval::writeJson(eval::makeTrajectoryReport(log, scores, gates, {lo, eo}), out_dir + "/report.json");
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitNothingUsable;
    }
    eval::printTrajectorySummary(std::cout, log, scores, gates);
    std::cout << "report: " << out_dir << "/report.json\n";
    if (!no_plots) {
      const auto plots = eval::writeTrajectoryPlots(log, scores, po, out_dir);
      if (plots.ok) {
        std::cout << "figures:";
        for (const auto& f : plots.figures) std::cout << " " << f;
        std::cout << "\n";
      } else {
        spdlog::warn("{}", plots.message);
      }
    }
    if (log.damaged) {
      spdlog::warn("{}: the log is damaged: the report covers its {} intact events only", log_path, log.events_read);
      return static_cast<int>(common::kExitInputDamaged);
    }
    return 0;
  });
}
