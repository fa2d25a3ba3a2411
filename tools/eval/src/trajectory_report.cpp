// report.json, summary, figures and TUM export of lcmloc-evaluate.
#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/status_timeline.hpp"
#include "lcmloc/eval/trajectory_report.hpp"

namespace lcmloc::eval {
namespace {

using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json statsJson(const ErrorStats& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
}

json consistencyJson(const ConsistencyStats& c) {
  if (c.samples == 0) return {{"samples", 0}, {"verdict", "none"}};
  return {{"dof", c.dof},
          {"samples", c.samples},
          {"mean", number(c.mean)},
          {"mean_bounds", {number(c.mean_lo), number(c.mean_hi)}},
          {"sample_bounds", {number(c.sample_lo), number(c.sample_hi)}},
          {"fraction_inside", c.fraction_inside},
          {"verdict", c.verdict},
          {"effective_samples", c.effective_samples},
          {"mean_bounds_effective", {number(c.mean_lo_effective), number(c.mean_hi_effective)}},
          {"verdict_effective", c.verdict_effective}};
}

json trackJson(const TrackScore& s) {
  json j;
  j["channel"] = s.channel;
  j["filters"] = s.filters;
  j["estimates"] = s.estimates;
  j["scored"] = s.scored;
  j["skipped"] = {{"before_truth", s.before_truth}, {"after_truth", s.after_truth}, {"truth_gap", s.in_truth_gap}};
  j["without_covariance"] = s.without_covariance;
  j["first_utime"] = s.first_utime;
  j["last_utime"] = s.last_utime;
  if (!s.calibration.empty()) {  // the final self-calibration estimates (filters that have them)
    json c = json::object();
    for (const auto& v : s.calibration) c[v.name] = {{"value", number(v.value)}, {"sigma", number(v.sigma)}};
    j["calibration"] = c;
  }
  if (s.scored == 0) {
    j["position_error_m"] = nullptr;
    j["heading_error_rad"] = nullptr;
    j["relative"] = nullptr;
    j["nees_xytheta"] = consistencyJson(s.nees3);
    j["nees_xy"] = consistencyJson(s.nees2);
    return j;
  }
  j["position_error_m"] = statsJson(s.position);
  j["position_error_m"]["final"] = s.final_error_m;
  if (s.has_heading)
    j["heading_error_rad"] = {{"rmse", s.heading.rmse}, {"mean_abs", s.heading.mean}, {"median_abs", s.heading.median},
                              {"p95_abs", s.heading.p95}, {"max_abs", s.heading.max}};
  else
    j["heading_error_rad"] = nullptr;
  json segs = json::array();
  for (const auto& d : s.drift)
    segs.push_back({{"length_m", d.length_m},
                    {"segments", d.segments},
                    {"mean_pct", d.segments ? json(d.mean_pct) : json(nullptr)},
                    {"median_pct", d.segments ? json(d.median_pct) : json(nullptr)},
                    {"max_pct", d.segments ? json(d.max_pct) : json(nullptr)}});
  j["relative"] = {{"path_length_m", s.path_length_m},
                   {"final_error_pct", s.path_length_m > 0 ? json(s.final_error_pct) : json(nullptr)},
                   {"segments", segs}};
  j["nees_xytheta"] = consistencyJson(s.nees3);
  j["nees_xy"] = consistencyJson(s.nees2);
  return j;
}

json gateGroupJson(const GateGroup& g) {
  return {{"filter", g.filter},
          {"sensor", g.sensor},
          {"decisions", g.decisions},
          {"accepted", g.accepted},
          {"rejected", g.rejected},
          {"ignored", g.ignored},
          {"reasons", g.reasons},
          {"nis_accepted", consistencyJson(g.nis)},
          {"nis_mean_dof", g.mean_dof},
          {"nis_mean_all", g.nis_mean_all},
          {"longest_rejection_run", g.longest_rejection_run},
          {"longest_rejection_s", g.longest_rejection_s}};
}

json gateListJson(const std::vector<GateGroup>& v) {
  json a = json::array();
  for (const auto& g : v) a.push_back(gateGroupJson(g));
  return a;
}

/// The 2D confidence ellipse of cov (sigma standard deviations) around (x, y) as a closed polyline.
void ellipse(std::ostream& f, double x, double y, const Eigen::Matrix2d& cov, double sigma) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  const Eigen::Vector2d l = es.eigenvalues().cwiseMax(0.0).cwiseSqrt() * sigma;
  const Eigen::Matrix2d v = es.eigenvectors();
  constexpr int kPoints = 48;
  for (int i = 0; i <= kPoints; ++i) {
    const double a = 2.0 * kPi * i / kPoints;
    const Eigen::Vector2d p = v * Eigen::Vector2d(l[0] * std::cos(a), l[1] * std::sin(a));
    f << x + p[0] << ' ' << y + p[1] << '\n';
  }
  f << '\n';
}

/// The log's track of a channel (every score has one).
const EstimateTrack* trackOf(const TrajectoryLog& log, const std::string& channel) {
  for (const auto& t : log.tracks)
    if (t.channel == channel) return &t;
  return nullptr;
}

/// Times of the report and the figures: seconds since the truth's first sample (0 without one).
int64_t timeOrigin(const TrajectoryLog& log) { return log.truth.empty() ? 0 : log.truth.front().utime; }

}  // namespace

json makeTrajectoryReport(const TrajectoryLog& log, const std::vector<TrackScore>& scores, const GateStats& gates,
                          const TrajectoryReportMeta& meta) {
  json j;
  json issues = json::array();
  for (const auto& i : log.issues)
    issues.push_back({{"event_index", i.event_index}, {"byte_offset", i.byte_offset}, {"what", i.what}});
  j["log"] = {{"path", log.path},
              {"file_size", log.file_size},
              {"events_read", log.events_read},
              {"bytes_unreadable", log.bytes_unreadable},
              {"damaged", log.damaged},
              {"interrupted", log.interrupted},
              {"channels", log.channel_counts},
              {"bad_utime", log.bad_utime},
              {"issues", issues}};
  j["settings"] = {{"pose_channel", meta.log.pose_channel},
                   {"all_pose_channels", meta.log.all_pose_channels},
                   {"truth_channel", meta.log.truth_channel},
                   {"gate_channel", meta.log.gate_channel},
                   {"segment_lengths_m", meta.eval.segment_lengths},
                   {"max_truth_gap_s", meta.eval.max_truth_gap_s},
                   {"confidence", meta.eval.confidence}};
  json truth = {{"type", log.truth_type.empty() ? json(nullptr) : json(log.truth_type)},
                {"samples", log.truth.size()},
                {"has_heading", !log.truth.empty() && log.truth.front().has_heading}};
  if (!log.truth.empty()) {
    truth["first_utime"] = log.truth.front().utime;
    truth["last_utime"] = log.truth.back().utime;
  }
  j["truth"] = truth;
  j["tracks"] = json::array();
  for (const auto& s : scores) {
    j["tracks"].push_back(trackJson(s));
    if (const EstimateTrack* t = trackOf(log, s.channel))
      j["tracks"].back()["status_timeline"] = statusTimelineJson(statusTimeline(*t, log.gates), timeOrigin(log));
  }
  j["gate"] = {{"decisions", log.gates.size()},
               {"by_filter_sensor", gateListJson(gates.by_filter_sensor)},
               {"by_filter", gateListJson(gates.by_filter)},
               {"by_sensor", gateListJson(gates.by_sensor)}};
  if (!log.faults.empty()) {
    json by = json::array();
    for (const auto& g : faultStatistics(log.gates, log.faults)) {
      const auto& c = g.counts;
      by.push_back({{"filter", g.filter}, {"accepted", c.accepted}, {"rejected", c.rejected}, {"ignored", c.ignored},
                    {"faults_decided", c.faults_decided}, {"faults_accepted", c.faults_accepted},
                    {"faults_rejected", c.faults_rejected}, {"valid_rejected", c.valid_rejected}});
    }
    j["faults"] = {{"announced", log.faults.size()}, {"by_filter", by}};
  }
  if (!log.unknown_identity.empty()) {
    json by = json::array();
    for (const auto& g : identityStatistics(log.gates, log.landmark_channel, log.unknown_identity))
      by.push_back({{"filter", g.filter}, {"known_decided", g.known_decided}, {"known_accepted", g.known_accepted},
                    {"unknown_decided", g.unknown_decided}, {"unknown_accepted", g.unknown_accepted}});
    j["unknown_identity"] = {{"landmark_observations", log.landmark_observations},
                             {"without_identity", log.unknown_identity.size()}, {"by_filter", by}};
  }
  if (const auto& c = meta.live_vs_replay)
    j["live_vs_replay"] = {{"filter", c->filter},
                           {"matched_poses", c->matched},
                           {"max_diff_m", c->max_diff_m >= 0 ? json(c->max_diff_m) : json(nullptr)}};
  return j;
}

void printTrajectorySummary(std::ostream& os, const TrajectoryLog& log, const std::vector<TrackScore>& scores,
                            const GateStats& gates, const std::optional<ReplayComparison>& live_vs_replay) {
  os << std::left << std::setw(22) << "channel" << std::right << std::setw(8) << "scored" << std::setw(9)
     << "RMSE[m]" << std::setw(9) << "med[m]" << std::setw(9) << "p95[m]" << std::setw(9) << "max[m]"
     << std::setw(10) << "hRMSE[d]" << std::setw(9) << "final%" << std::setw(10) << "NEES3" << std::setw(10)
     << "NEES2" << "  covariance\n";
  for (const auto& s : scores) {
    os << std::left << std::setw(22) << withoutControlCharacters(s.channel) << std::right << std::setw(8) << s.scored << std::fixed;
    if (s.scored == 0) {
      os << "   (no estimate inside the truth span)\n";
      continue;
    }
    os << std::setprecision(3) << std::setw(9) << s.position.rmse << std::setw(9) << s.position.median << std::setw(9)
       << s.position.p95 << std::setw(9) << s.position.max;
    if (s.has_heading) os << std::setprecision(2) << std::setw(10) << s.heading.rmse * 180.0 / kPi;
    else os << std::setw(10) << "-";
    if (s.path_length_m > 0) os << std::setprecision(3) << std::setw(9) << s.final_error_pct;
    else os << std::setw(9) << "-";
    auto nees = [&](const ConsistencyStats& c) {
      if (c.samples) os << std::setprecision(2) << std::setw(10) << c.mean;
      else os << std::setw(10) << "-";
    };
    nees(s.nees3);
    nees(s.nees2);
    const auto& c = s.nees3.samples ? s.nees3 : s.nees2;
    os << "  " << c.verdict;
    if (c.samples)
      os << " (" << (s.nees3.samples ? 3 : 2) << " dof: mean in [" << std::setprecision(2) << c.mean_lo << ", "
         << c.mean_hi << "], " << std::setprecision(1) << 100.0 * c.fraction_inside
         << "% inside per-sample 95%); " << c.verdict_effective << " for " << std::setprecision(0)
         << c.effective_samples << " effective samples (mean in [" << std::setprecision(2) << c.mean_lo_effective
         << ", " << c.mean_hi_effective << "])";
    os << "\n";
    if (s.before_truth + s.after_truth + s.in_truth_gap > 0)
      os << "  skipped: " << s.before_truth << " before the truth, " << s.after_truth << " after, " << s.in_truth_gap
         << " in truth gaps\n";
    for (const auto& d : s.drift)
      if (d.segments)
        os << "  drift over " << std::setprecision(0) << d.length_m << " m: mean " << std::setprecision(2)
           << d.mean_pct << "%, max " << d.max_pct << "% (" << d.segments << " segments)\n";
    if (!s.calibration.empty()) {
      os << "  calibration (final):" << std::defaultfloat << std::setprecision(4);
      for (const auto& c : s.calibration) os << " " << c.name << " " << c.value << " +- " << std::setprecision(2) << c.sigma << std::setprecision(4);
      os << std::fixed << "\n";
    }
  }
  if (!gates.by_filter_sensor.empty()) {
    // (the filter column as wide as its longest name: replay:dead_reckoning is 21 characters)
    int fw = 18;
    for (const auto& g : gates.by_filter_sensor)
      fw = std::max(fw, static_cast<int>(withoutControlCharacters(g.filter).size()) + 1);
    os << std::left << std::setw(fw) << "gate filter" << std::setw(18) << "sensor" << std::right << std::setw(9)
       << "accepted" << std::setw(9) << "rejected" << std::setw(10) << "NIS mean" << std::setw(6) << "dof"
       << std::setw(14) << "rej. run[s]" << "  reasons\n";
    for (const auto& g : gates.by_filter_sensor) {
      os << std::left << std::setw(fw) << withoutControlCharacters(g.filter) << std::setw(18) << withoutControlCharacters(g.sensor) << std::right << std::setw(9)
         << g.accepted << std::setw(9) << g.rejected << std::setprecision(2);
      if (g.nis.samples) os << std::setw(10) << g.nis.mean << std::setw(6) << g.mean_dof << "  ";
      else os << std::setw(10) << "-" << std::setw(6) << "-" << "  ";
      os << std::setw(12) << std::fixed << std::setprecision(1) << g.longest_rejection_s << std::defaultfloat << "  ";
      bool first = true;
      for (const auto& [r, n] : g.reasons) {
        os << (first ? "" : ", ") << withoutControlCharacters(r) << " " << n;
        first = false;
      }
      os << "\n";
    }
  }
  if (!log.faults.empty()) {
    os << log.faults.size() << " fault(s) announced on FAULT_EVENTS\n"
       << std::left << std::setw(22) << "fault filter" << std::right << std::setw(16) << "faults rejected"
       << std::setw(16) << "faults accepted" << std::setw(16) << "valid rejected" << "\n";
    for (const auto& g : faultStatistics(log.gates, log.faults))
      os << std::left << std::setw(22) << withoutControlCharacters(g.filter) << std::right << std::setw(16)
         << g.counts.faults_rejected << std::setw(16) << g.counts.faults_accepted << std::setw(16)
         << g.counts.valid_rejected << "\n";
  }
  if (!log.unknown_identity.empty()) {
    os << log.unknown_identity.size() << " of " << log.landmark_observations
       << " landmark observation(s) without identity (landmark_id -1)\n"
       << std::left << std::setw(22) << "identity filter" << std::right << std::setw(18) << "known accepted"
       << std::setw(22) << "unknown accepted" << "\n";
    for (const auto& g : identityStatistics(log.gates, log.landmark_channel, log.unknown_identity))
      os << std::left << std::setw(22) << withoutControlCharacters(g.filter) << std::right << std::setw(18)
         << (std::to_string(g.known_accepted) + " of " + std::to_string(g.known_decided)) << std::setw(22)
         << (std::to_string(g.unknown_accepted) + " of " + std::to_string(g.unknown_decided)) << "\n";
  }
  for (const auto& s : scores)
    if (const EstimateTrack* t = trackOf(log, s.channel)) {
      const StatusTimeline st = statusTimeline(*t, log.gates);
      if (st.eventful()) os << statusSummary(st, timeOrigin(log)) << "\n";
    }
  if (live_vs_replay) {
    os << "recorded " << withoutControlCharacters(live_vs_replay->filter) << " against its replay: ";
    if (live_vs_replay->matched)
      os << live_vs_replay->matched << " estimates at equal times, largest difference " << std::setprecision(6)
         << live_vs_replay->max_diff_m << " m\n";
    else
      os << "no estimate at an equal time\n";
  }
  os << "log: " << log.events_read << " events, " << log.file_size << " bytes";
  if (log.damaged) os << ", DAMAGED (" << log.bytes_unreadable << " bytes unreadable)";
  os << ", " << log.issues.size() << " issue(s)\n";
  printIssues(os, log.issues);
  printBadUtime(os, log.bad_utime);
}

PlotResult writeTrajectoryPlots(const TrajectoryLog& log, const std::vector<TrackScore>& scores,
                                const TrajectoryPlotOptions& opt, const std::string& dir) {
  PlotResult res;
  const int64_t t0 = timeOrigin(log);
  {
    std::ofstream f(dir + "/truth.dat");
    f << "# t[s] x[m] y[m] heading[rad]\n" << std::setprecision(10);
    for (const auto& t : log.truth) f << secondsSince(t.utime, t0) << ' ' << t.x << ' ' << t.y << ' ' << t.heading << '\n';
  }
  std::ofstream gp(dir + "/evaluate.gp");
  gp << "# Generated by lcmloc-evaluate; rerun with: gnuplot evaluate.gp\n"
        "set terminal pngcairo size 1100,800 noenhanced font 'Sans,12'\n"
        "set datafile missing '?'\nset grid\nset key outside right top\n";
  std::vector<std::string> channels;
  for (const auto& s : scores) channels.push_back(s.channel);
  const auto stems = uniqueStems(channels);  // POSE_A.B and POSE_A_B must not share files
  auto str = [](double v) {
    std::ostringstream o;
    o << v;
    return o.str();
  };
  for (std::size_t i = 0; i < scores.size(); ++i) {
    const auto& s = scores[i];
    if (s.scored == 0) continue;
    const std::string& st = stems[i];
    const std::string track = "track_" + st + ".dat", ell = "ellipses_" + st + ".dat";
    {
      std::ofstream f(dir + "/" + track);
      f << "# t[s] x[m] y[m] theta[rad] err[m] err_heading[deg] nees3 nees2 (? = not computed)\n"
        << std::setprecision(10);
      for (const auto& p : s.points) {
        if (p.after_skip) f << '\n';  // no line across estimates that were not scored
        f << secondsSince(p.utime, t0) << ' ' << p.x << ' ' << p.y << ' ' << p.theta << ' ' << p.err << ' ';
        if (s.has_heading) f << p.err_heading * 180.0 / kPi << ' ';
        else f << "? ";
        if (p.nees3 >= 0) f << p.nees3 << ' ';
        else f << "? ";
        if (p.nees2 >= 0) f << p.nees2 << '\n';
        else f << "?\n";
      }
    }
    int64_t with_cov = 0;
    for (const auto& p : s.points) with_cov += p.has_cov ? 1 : 0;
    {
      std::ofstream f(dir + "/" + ell);
      f << "# " << opt.ellipse_sigma << "-sigma position ellipses: x[m] y[m], one closed curve per block\n"
        << std::setprecision(10);
      const int64_t every = opt.ellipse_every > 0 ? opt.ellipse_every : std::max<int64_t>(1, with_cov / 40);
      int64_t k = 0;
      for (const auto& p : s.points)
        if (p.has_cov && (k++ % every) == 0) ellipse(f, p.x, p.y, p.cov_xy, opt.ellipse_sigma);
    }
    // Channel names come from the log: into the script only through gnuplotQuote.
    gp << "set output " << gnuplotQuote("trajectory_" + st + ".png") << "\n"
       << "set title "
       << gnuplotQuote("Trajectory: " + s.channel + " against the truth (" + str(opt.ellipse_sigma) +
                       "-sigma position ellipses)")
       << "\n"
          "set xlabel 'X [m]'\nset ylabel 'Y [m]'\nset size ratio -1\nset key inside left bottom box opaque\n"
          "plot 'truth.dat' u 2:3 w l lw 3 lc rgb '#000000' t 'truth', \\\n  "
       << gnuplotQuote(track) << " u 2:3 w l lw 2 lc rgb '#0072b2' t " << gnuplotQuote(s.channel);
    if (with_cov) gp << ", \\\n  " << gnuplotQuote(ell) << " u 1:2 w l lw 1 lc rgb '#d55e00' t 'covariance'";
    gp << "\nset size noratio\nset key outside right top nobox\n";

    gp << "set output " << gnuplotQuote("errors_" + st + ".png") << "\n"
       << "set multiplot layout " << (s.has_heading ? 2 : 1) << ",1 title " << gnuplotQuote("Errors of " + s.channel)
       << "\n"
       << "set xlabel 'time [s]'\nset ylabel 'position error [m]'\nunset title\n"
       << "set key inside right top box opaque\n"
       << "plot " << gnuplotQuote(track) << " u 1:5 w l lw 2 lc rgb '#0072b2' t '|position error|'\n";
    if (s.has_heading)
      gp << "set ylabel 'heading error [deg]'\nplot " << gnuplotQuote(track)
         << " u 1:6 w l lw 2 lc rgb '#009e73' t 'heading error (wrapped)'\n";
    gp << "unset multiplot\nset key outside right top nobox\n";

    if (s.nees2.samples) {
      const bool three = s.nees3.samples > 0;
      gp << "set output " << gnuplotQuote("nees_" + st + ".png") << "\n"
         << "set multiplot layout " << (three ? 2 : 1) << ",1 title "
         << gnuplotQuote("NEES of " + s.channel + " (log scale) with the two-sided 95% bounds") << "\n"
         << "set xlabel 'time [s]'\nset logscale y\nset format y '%g'\nunset title\n"
         << "set key inside right bottom box opaque font ',10'\n" << std::setprecision(3);
      auto panel = [&](const ConsistencyStats& c, int column, const char* name) {
        gp << "set ylabel 'NEES " << name << "'\n"
           << "plot " << gnuplotQuote(track) << " u 1:" << column << " w l lw 1 lc rgb '#0072b2' t 'NEES " << name << "', \\\n  "
           << c.sample_lo << " w l dt 2 lw 2 lc rgb '#7f7f7f' t 'per-sample 95% [" << c.sample_lo << ", "
           << c.sample_hi << "]', \\\n  " << c.sample_hi << " w l dt 2 lw 2 lc rgb '#7f7f7f' notitle, \\\n  "
           << c.mean << " w l lw 2 lc rgb '#d55e00' t sprintf('mean %.3g (bounds %.3g..%.3g): " << c.verdict
           << "', " << c.mean << ", " << c.mean_lo << ", " << c.mean_hi << "), \\\n  " << c.dof
           << " w l dt 3 lw 2 lc rgb '#000000' t 'dof " << c.dof << "'\n";
      };
      if (three) panel(s.nees3, 7, "(x, y, theta)");
      panel(s.nees2, 8, "(x, y)");
      gp << "unset logscale y\nset format y '% h'\nunset multiplot\nset key outside right top nobox font ',12'\n"
         << std::setprecision(6);
      res.figures.push_back("nees_" + st + ".png");
    }
    res.figures.insert(res.figures.end() - (s.nees2.samples ? 1 : 0),
                       {"trajectory_" + st + ".png", "errors_" + st + ".png"});
    if (const EstimateTrack* t = trackOf(log, s.channel))
      writeStatusPlot(gp, statusTimeline(*t, log.gates), t0, dir, st, res.figures);
  }
  writeGatePlots(gp, log, t0, dir, res.figures);
  gp << "set output\n";
  gp.close();
  if (res.figures.empty()) {
    res.message = "nothing to plot";
    return res;
  }
  return drawFigures(res, dir, "evaluate.gp");
}

std::string tumLine(int64_t utime, double x, double y, double yaw) {
  const char* sign = utime < 0 ? "-" : "";
  const uint64_t a = utime < 0 ? static_cast<uint64_t>(-(utime + 1)) + 1 : static_cast<uint64_t>(utime);
  char buf[192];
  std::snprintf(buf, sizeof buf, "%s%" PRIu64 ".%06" PRIu64 " %.6f %.6f 0 0 0 %.9f %.9f", sign, a / 1000000u,
                a % 1000000u, x, y, std::sin(yaw / 2.0), std::cos(yaw / 2.0));
  return buf;
}

namespace {
template <typename It, typename F>
void writeLines(const std::string& path, It begin, It end, F line) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write '" + path + "'");
  f << "# timestamp tx ty tz qx qy qz qw\n";
  for (auto it = begin; it != end; ++it) f << line(*it) << '\n';
  if (!f) throw std::runtime_error("error while writing '" + path + "'");
}
}  // namespace

std::size_t writeTum(const std::string& path, const std::vector<Estimate>& poses) {
  // TUM tools want unique timestamps: of several estimates at one utime the last is written.
  std::vector<Estimate> unique;
  for (const auto& e : poses) {
    if (!unique.empty() && unique.back().utime == e.utime) unique.back() = e;
    else unique.push_back(e);
  }
  writeLines(path, unique.begin(), unique.end(), [](const Estimate& e) { return tumLine(e.utime, e.x, e.y, e.theta); });
  return unique.size();
}

void writeTum(const std::string& path, const std::vector<TruthPose>& truth) {
  writeLines(path, truth.begin(), truth.end(),
             [](const TruthPose& t) { return tumLine(t.utime, t.x, t.y, t.has_heading ? t.heading : 0.0); });
}

}  // namespace lcmloc::eval
