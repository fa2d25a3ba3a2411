// lcmloc-evaluate's options and run (see evaluate_command.hpp; definitions: docs/evaluate.md).
#include "lcmloc/eval/evaluate_command.hpp"

#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>

#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/replay_filters.hpp"

namespace lcmloc::eval {
namespace {

constexpr int kExitNothingUsable = app::kExitRuntimeError;
constexpr int kExitBadConfig = app::kExitConfigError;

std::string channelList(const std::map<std::string, int64_t>& counts) {
  if (counts.empty()) return "none";
  std::ostringstream s;
  bool first = true;
  for (const auto& [c, n] : counts) {
    s << (first ? "" : ", ") << withoutControlCharacters(c) << " (" << n << ")";
    first = false;
  }
  return s.str();
}

std::string spanText(int64_t a, int64_t b) {
  std::ostringstream s;
  s << std::fixed;
  s.precision(3);
  s << "[" << static_cast<double>(a) * 1e-6 << " s, " << static_cast<double>(b) * 1e-6 << " s]";
  return s.str();
}

}  // namespace

void addEvaluateOptions(CLI::App& app, EvaluateCommand& c) {
  app.add_option("log", c.log_path, "LCM log file holding estimates (and ground truth)")->required();
  c.o_pose =
      app.add_option("--pose-channel", c.lo.pose_channel, "channel of the estimates (pose_t)")->capture_default_str();
  app.add_flag("--all-poses", c.lo.all_pose_channels, "also score every other POSE_* channel (shadow filters)");
  c.o_truth = app.add_option("--truth-channel", c.lo.truth_channel,
                                 "channel of the reference: ground_truth_t, or gps_fix_t (needs a datum)")
                      ->capture_default_str();
  c.o_gate = app.add_option("--gate-channel", c.lo.gate_channel, "channel of the gate decisions (gate_decision_t)")
                     ->capture_default_str();
  app.add_option("--datum", c.datum, "LAT,LON[,ALT]: origin of the local frame for gps_fix_t truth [deg, deg, m]")
      ->delimiter(',')
      ->expected(1, 3)  // 2 or 3, checked below (a minimum above 1 would print "x 2" in --help)
      ->type_name("LAT,LON[,ALT]");
  app::addOutputOption(app, c.out_dir, "output directory for report.json and figures")->capture_default_str();
  app::addOverwriteFlag(app, c.overwrite);
  app.add_option("--tum-dir", c.tum_dir, "write estimate.tum (estimate_<CHANNEL>.tum for POSE_*) and truth.tum here");
  app.add_flag("--export-only", c.export_only, "only export TUM files (--tum-dir): no truth needed, no scoring");
  app.add_option("--segment-lengths", c.eo.segment_lengths, "drift segment lengths [m]")
      ->delimiter(',')->capture_default_str()->check(app::positive());
  app.add_option("--max-truth-gap", c.eo.max_truth_gap_s,
                 "estimates between truth samples further apart than this are not scored [s] (0 = no limit)")
      ->capture_default_str()->check(app::nonNegative());
  app.add_option("--confidence", c.eo.confidence, "probability of the two-sided chi-square intervals")
      ->capture_default_str()->check(CLI::Range(0.5, 0.9999));
  app.add_option("--ellipse-every", c.po.ellipse_every, "covariance ellipse at every k-th scored estimate (0 = about 40)")
      ->capture_default_str()->check(app::nonNegative());
  app.add_option("--ellipse-sigma", c.po.ellipse_sigma, "ellipse size in standard deviations")
      ->capture_default_str()->check(app::positive());
  app.add_flag("--no-plots", c.no_plots, "do not draw figures");
  app.add_option("--filters", c.filters,
                 "also replay the log's sensor channels through the fusion daemon's code with each of these filters "
                 "(the config's fusion.filter with that type) and score them as replay:<TYPE>, with the replay's "
                 "gate decisions")
      ->delimiter(',');
}

int runEvaluate(EvaluateCommand c) {
  const std::string &log_path = c.log_path, &out_dir = c.out_dir, &tum_dir = c.tum_dir, &config_path = c.config_path;
  const std::vector<double>& datum = c.datum;
  const bool export_only = c.export_only, no_plots = c.no_plots;
  TrajectoryLogOptions& lo = c.lo;
  const EvaluateOptions& eo = c.eo;
  const TrajectoryPlotOptions& po = c.po;
  const CLI::Option *o_pose = c.o_pose, *o_truth = c.o_truth, *o_gate = c.o_gate;
  app::requireInputFile(log_path, "input log");
  app::refuseExistingOutput(tum_dir, c.overwrite, "--tum-dir");
  if (!export_only) app::refuseExistingOutput(out_dir, c.overwrite);
  if (export_only && tum_dir.empty()) {
    spdlog::error("--export-only needs --tum-dir DIR");
    return kExitBadConfig;
  }
  if (datum.size() == 1) {
    spdlog::error("--datum needs LAT,LON or LAT,LON,ALT (got one number)");
    return kExitBadConfig;
  }
  app::SystemConfig cfg;  // built-in defaults without --config
  try {
    if (!config_path.empty()) {
      cfg = app::loadSystemConfig(config_path);
      if (!o_pose->count()) lo.pose_channel = cfg.channels.pose;
      if (!o_truth->count()) lo.truth_channel = cfg.channels.ground_truth;
      if (!o_gate->count()) lo.gate_channel = cfg.channels.gate;
      lo.fault_channel = cfg.channels.fault_events;
      lo.landmark_channel = cfg.channels.landmarks;
      lo.datum = cfg.datum;
    }
    if (!datum.empty()) {
      bus::Datum d;
      d.latitude = datum[0];
      d.longitude = datum[1];
      d.altitude = datum.size() > 2 ? datum[2] : 0.0;
      bus::LocalFrame check(d);  // throws std::invalid_argument when out of range
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

  TrajectoryLog log;
  try {
    // A progress line every 2 s of wall time on long logs.
    const auto start = std::chrono::steady_clock::now();
    auto last = start;
    log = readTrajectoryLog(log_path, lo, &app::stopFlag(), [&](int64_t pos, int64_t size) {
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
                    "channel?", flag, app::printable(ch), n->second,
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

  std::optional<ReplayComparison> live_vs_replay;
  if (!c.filters.empty()) {
    try {
      addReplayedFilters(log, log_path, cfg, c.filters, out_dir, &app::stopFlag());
      // The recorded estimates against the replay of their filter: equal where the run was deterministic.
      const auto& recorded = log.tracks.front();
      for (const auto& t : log.tracks)
        if (!recorded.filters.empty() && t.channel == replayedName(recorded.filters.back()))
          live_vs_replay = compareTracks(recorded, t);
    } catch (const app::ConfigError& e) {
      spdlog::error("{}", e.what());
      return kExitBadConfig;
    } catch (const std::invalid_argument& e) {
      spdlog::error("{}", e.what());
      return kExitBadConfig;
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitNothingUsable;
    }
  }

  // Tracks with estimates; the pose channel first.
  std::vector<EstimateTrack> tracks;
  for (const auto& t : log.tracks)
    if (!t.poses.empty()) tracks.push_back(t);
  if (tracks.empty()) {
    spdlog::error("{}: no estimates (pose_t) on channel {}{} in {} events; channels in the log: {}{}", log_path,
                  lo.pose_channel, lo.all_pose_channels ? " or POSE_*" : "", log.events_read,
                  channelList(log.channel_counts),
                  c.filters.empty() ? ". A log of sensor channels is replayed and scored with --filters TYPE,..." : "");
    // (nothing to evaluate in a damaged log: an empty one, one that is no log: the damage is why)
    return log.damaged ? static_cast<int>(app::kExitInputDamaged) : kExitNothingUsable;
  }
  if (log.tracks.front().poses.empty() && c.filters.empty())  // (a sensor log to replay has none)
    spdlog::warn("{}: no estimates on {}; scoring {}", log_path, lo.pose_channel, withoutControlCharacters(tracks.front().channel));

  if (!tum_dir.empty()) {
    try {
      std::filesystem::create_directories(tum_dir);
      std::vector<std::string> channels;
      for (const auto& t : tracks) channels.push_back(t.channel);
      const auto stems = uniqueStems(channels);  // a channel name is no path
      for (std::size_t i = 0; i < tracks.size(); ++i) {
        const auto& t = tracks[i];
        const std::string name = t.channel == lo.pose_channel ? "estimate" : "estimate_" + stems[i];
        const std::string file = tum_dir + "/" + name + ".tum";
        const auto n = writeTum(file, t.poses);
        std::cout << "TUM: " << file << " (" << n << " poses";
        if (n != t.poses.size()) std::cout << "; " << t.poses.size() - n << " with a repeated utime left out";
        std::cout << ")\n";
      }
      if (!log.truth.empty()) {
        writeTum(tum_dir + "/truth.tum", log.truth);
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

  std::vector<TrackScore> scores;
  bool any_scored = false;
  for (const auto& t : tracks) {
    scores.push_back(scoreTrack(t, log.truth, eo));
    const auto& s = scores.back();
    any_scored = any_scored || s.scored > 0;
    if (s.before_truth + s.after_truth + s.in_truth_gap > 0)
      spdlog::warn("{}: {} of {} estimates not scored: {} before the first truth sample, {} after the last, {} in "
                   "truth gaps longer than {} s",
                   withoutControlCharacters(s.channel), s.before_truth + s.after_truth + s.in_truth_gap, s.estimates, s.before_truth,
                   s.after_truth, s.in_truth_gap, eo.max_truth_gap_s);
  }
  if (!any_scored) {
    const auto& t = tracks.front();
    spdlog::error("{}: no estimate lies inside the ground truth: estimates on {} span {}, truth on {} spans {}{}",
                  log_path, withoutControlCharacters(t.channel), spanText(t.poses.front().utime, t.poses.back().utime), lo.truth_channel,
                  spanText(log.truth.front().utime, log.truth.back().utime),
                  eo.max_truth_gap_s > 0 ? " (gaps over --max-truth-gap excluded)" : "");
    return kExitNothingUsable;
  }
  const auto gates = gateStatistics(log.gates, eo.confidence);

  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    spdlog::error("cannot create output directory '{}': {}", out_dir, ec.message());
    return kExitNothingUsable;
  }
  try {
    writeJson(makeTrajectoryReport(log, scores, gates, {lo, eo, live_vs_replay}), out_dir + "/report.json");
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitNothingUsable;
  }
  printTrajectorySummary(std::cout, log, scores, gates, live_vs_replay);
  std::cout << "report: " << out_dir << "/report.json\n";
  if (!no_plots) {
    const auto plots = writeTrajectoryPlots(log, scores, po, out_dir);
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
    return static_cast<int>(app::kExitInputDamaged);
  }
  return 0;
}

}  // namespace lcmloc::eval
