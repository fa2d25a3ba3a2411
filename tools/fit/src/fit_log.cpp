#include "lcmloc/fit/fit_log.hpp"

#include <algorithm>
#include <cmath>


#include "lcmloc/app/csv.hpp"
#include "lcmloc/bus/convert.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/logio/log_reader.hpp"

namespace lcmloc::fit {

namespace {
/// A converted message kept, or false (refused by the conversion).
template <typename T>
bool keep(std::optional<T>&& v, std::vector<T>& into) {
  if (!v) return false;
  into.push_back(std::move(*v));
  return true;
}
}  // namespace

LogRead readRecording(const std::string& log, const app::SystemConfig& cfg) {
  LogRead out;
  Recording& r = out.recording;
  r.wheelbase = cfg.fusion.filter.wheelbase;
  r.pw_distance = cfg.fusion.filter.pw_distance > 0 ? cfg.fusion.filter.pw_distance : 1.0;
  if (!cfg.fusion.map_file.empty()) r.map = app::csv::loadMap(cfg.fusion.map_file);
  const bus::LocalFrame frame(cfg.datum);
  const auto& ch = cfg.channels;
  auto take = [&out](const logio::RawEvent& ev, auto& m, auto&& convert) {
    if (!logio::decodeEvent(ev, m)) {
      ++out.refused;
      return;
    }
    if (!convert(m)) ++out.refused;
  };
  const logio::ScanSummary scan = logio::scanLog(log, [&](const logio::RawEvent& ev) {
    const std::string& c = *ev.channel;
    std::string why;
    if (c == ch.ground_truth) {
      lcmloc::ground_truth_t m{};
      take(ev, m, [&](const lcmloc::ground_truth_t& t) {
        if (!std::isfinite(t.x) || !std::isfinite(t.y)) return false;
        r.truth.push_back({t.utime, t.x, t.y, std::isfinite(t.heading) ? t.heading : 0.0, std::isfinite(t.heading)});
        return true;
      });
    } else if (c == ch.odometry) {
      lcmloc::odometry_t m{};
      take(ev, m, [&](const lcmloc::odometry_t& o) { return keep(bus::toCore(o, &why), r.odometry); });
    } else if (c == ch.landmarks) {
      lcmloc::landmark_obs_t m{};
      take(ev, m, [&](const lcmloc::landmark_obs_t& o) { return keep(bus::toCore(o, c, &why), r.landmarks); });
    } else if (c == ch.beacons) {
      lcmloc::beacon_range_t m{};
      take(ev, m, [&](const lcmloc::beacon_range_t& o) { return keep(bus::toCore(o, c, &why), r.beacons); });
    } else if (c == ch.gps) {
      lcmloc::gps_fix_t m{};
      take(ev, m, [&](const lcmloc::gps_fix_t& o) { return keep(bus::toCore(o, c, frame, &why), r.gps); });
    }
  });
  out.damaged = scan.damaged;
  auto byTime = [](const auto& a, const auto& b) { return a.utime < b.utime; };
  std::stable_sort(r.truth.begin(), r.truth.end(), byTime);
  std::stable_sort(r.odometry.begin(), r.odometry.end(), byTime);
  std::stable_sort(r.landmarks.begin(), r.landmarks.end(), byTime);
  std::stable_sort(r.beacons.begin(), r.beacons.end(), byTime);
  std::stable_sort(r.gps.begin(), r.gps.end(), byTime);
  return out;
}

}  // namespace lcmloc::fit
