#include "lcmloc/eval/status_timeline.hpp"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <set>

#include <spdlog/fmt/fmt.h>

#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::eval {

std::string statusName(int status) {
  switch (status) {
    case lcmloc::pose_t::STATUS_OK: return "ok";
    case lcmloc::pose_t::STATUS_DEAD_RECKONING: return "dead_reckoning";
    case lcmloc::pose_t::STATUS_LOCKOUT: return "lockout";
    case lcmloc::pose_t::STATUS_UNINITIALIZED: return "uninitialized";
    default: return std::to_string(status);
  }
}

bool StatusTimeline::eventful() const {
  return !relocalizations.empty() ||
         std::any_of(spans.begin(), spans.end(), [](const StatusSpan& s) { return s.status != lcmloc::pose_t::STATUS_OK; });
}

StatusTimeline statusTimeline(const EstimateTrack& track, const std::vector<GateRecord>& gates) {
  StatusTimeline t;
  t.channel = track.channel;
  for (const auto& e : track.poses) {
    if (t.spans.empty() || t.spans.back().status != e.status) {
      if (!t.spans.empty()) t.spans.back().to_utime = e.utime;
      t.spans.push_back({e.status, e.utime, e.utime, 0});
    }
    ++t.spans.back().estimates;
  }
  if (!t.spans.empty()) t.spans.back().to_utime = std::max(t.spans.back().to_utime, track.poses.back().utime);
  for (const auto& s : t.spans) {
    if (s.status == lcmloc::pose_t::STATUS_LOCKOUT) {
      ++t.lockouts;
      t.lockout_s += s.seconds();
      t.longest_lockout_s = std::max(t.longest_lockout_s, s.seconds());
    } else if (s.status == lcmloc::pose_t::STATUS_DEAD_RECKONING) {
      t.dead_reckoning_s += s.seconds();
    }
  }
  const std::set<std::string> filters(track.filters.begin(), track.filters.end());
  for (const auto& g : gates)
    // (a track lcmloc-evaluate replayed is named after its filter, "replay:ukf_landmarks", as are
    // its gate decisions; a recorded track's decisions carry the filter's own name)
    if (g.reason == "relocalized" && (filters.count(g.filter) || g.filter == track.channel))
      t.relocalizations.push_back({g.utime, g.filter, g.sensor});
  std::stable_sort(t.relocalizations.begin(), t.relocalizations.end(),
                   [](const auto& a, const auto& b) { return a.utime < b.utime; });
  return t;
}

nlohmann::json statusTimelineJson(const StatusTimeline& t, int64_t t0) {
  nlohmann::json spans = nlohmann::json::array(), reloc = nlohmann::json::array();
  for (const auto& s : t.spans)
    spans.push_back({{"status", statusName(s.status)},
                     {"from_s", secondsSince(s.from_utime, t0)},
                     {"to_s", secondsSince(s.to_utime, t0)},
                     {"from_utime", s.from_utime},
                     {"to_utime", s.to_utime},
                     {"estimates", s.estimates}});
  for (const auto& r : t.relocalizations)
    reloc.push_back({{"t_s", secondsSince(r.utime, t0)}, {"utime", r.utime}, {"filter", r.filter}, {"sensor", r.sensor}});
  return {{"lockouts", t.lockouts},
          {"lockout_s", t.lockout_s},
          {"longest_lockout_s", t.longest_lockout_s},
          {"dead_reckoning_s", t.dead_reckoning_s},
          {"relocalizations", reloc},
          {"spans", spans}};
}

std::string statusSummary(const StatusTimeline& t, int64_t t0) {
  std::string s = fmt::format("{} status: {} lock-out(s), {:.1f} s in lock-out (longest {:.1f} s), {:.1f} s dead "
                              "reckoning, {} re-localization(s)",
                              withoutControlCharacters(t.channel), t.lockouts, t.lockout_s, t.longest_lockout_s, t.dead_reckoning_s,
                              t.relocalizations.size());
  const std::size_t shown = std::min<std::size_t>(t.relocalizations.size(), 5);
  for (std::size_t i = 0; i < shown; ++i)
    s += fmt::format("{}{:.1f} s", i == 0 ? " at " : ", ", secondsSince(t.relocalizations[i].utime, t0));
  if (shown < t.relocalizations.size()) s += ", ...";
  return s;
}

void writeStatusPlot(std::ostream& gp, const StatusTimeline& t, int64_t t0, const std::string& dir,
                     const std::string& stem, std::vector<std::string>& figures) {
  if (!t.eventful()) return;
  const std::string data = "status_" + stem + ".dat", marks = "relocalized_" + stem + ".dat",
                    png = "status_" + stem + ".png";
  {
    std::ofstream f(dir + "/" + data);  // a step line: each span from its start to its end
    f << "# t[s] status (0 ok, 1 dead reckoning, 2 lock-out, 3 uninitialized)\n" << std::setprecision(10);
    for (const auto& s : t.spans)
      f << secondsSince(s.from_utime, t0) << ' ' << s.status << '\n' << secondsSince(s.to_utime, t0) << ' ' << s.status << '\n';
  }
  {
    std::ofstream f(dir + "/" + marks);
    f << "# t[s] re-localization\n" << std::setprecision(10);
    for (const auto& r : t.relocalizations) f << secondsSince(r.utime, t0) << " 0\n";
  }
  gp << "set output " << gnuplotQuote(png) << "\n"
     << "set title " << gnuplotQuote("Status of " + t.channel + ": lock-outs and re-localizations") << "\n"
     << "set xlabel 'time [s]'\nset ylabel 'status'\nset yrange [-0.5:3.5]\n"
     << "set ytics ('ok' 0, 'dead reckoning' 1, 'lock-out' 2, 'uninitialized' 3)\n"
     << "set key inside right top box opaque\n"
     << "plot " << gnuplotQuote(data) << " u 1:2 w l lw 2 lc rgb '#0072b2' t 'status'";
  if (!t.relocalizations.empty())
    gp << ", \\\n  " << gnuplotQuote(marks) << " u 1:2 w p pt 9 ps 2 lc rgb '#d55e00' t 're-localized'";
  gp << "\nset autoscale y\nset ytics autofreq\n";
  figures.push_back(png);
}

}  // namespace lcmloc::eval
