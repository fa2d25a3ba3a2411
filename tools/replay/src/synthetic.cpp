// Synthetic logs from the simulator's own models (lib/sim): laps of an oval track.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/replay/log_bus.hpp"
#include "lcmloc/replay/replay.hpp"

namespace lcmloc::replay {

sim::ScenarioConfig ovalScenario(const sim::ScenarioConfig& base, const OvalTrack& t, double duration_s) {
  sim::ScenarioConfig sc = base;
  const double k = 1.0 / t.radius, half = M_PI * t.radius;
  const double lap = 2.0 * t.straight + 2.0 * half;
  const int laps = static_cast<int>(std::ceil(duration_s * base.vehicle.speed / lap)) + 2;
  sc.path.segments.clear();
  for (int i = 0; i < laps; ++i) {
    sc.path.segments.push_back({t.straight, 0.0});
    sc.path.segments.push_back({half, k});
    sc.path.segments.push_back({t.straight, 0.0});
    sc.path.segments.push_back({half, k});
  }
  // Markers along the first lap only: later laps pass over the same magnets.
  sc.markers.first_at = t.marker_spacing;
  sc.markers.spacing = t.marker_spacing;
  sc.markers.count = static_cast<int>(std::floor((lap - t.marker_spacing) / t.marker_spacing));
  sc.faults.clear();
  return sc;
}

SyntheticLogStats writeSyntheticLog(const sim::ScenarioConfig& sc, double duration_s, const std::string& path,
                                    const app::ChannelConfig& channels,
                                    const std::function<bool(double)>& progress) {
  SyntheticLogStats st;
  const sim::Path track(sc.path);
  const auto map = sim::makeMarkerMap(track, sc.markers);
  st.markers = static_cast<int64_t>(map.size());
  const int64_t end_utime = sc.vehicle.start_utime + static_cast<int64_t>(std::llround(duration_s * 1e6));
  sim::VehicleSim vehicle(sc.vehicle, track, track.length() - 1.0, sim::componentSeed(sc.seed, "vehicle"));
  sim::OdometrySensor odometry(sc.odometry, sc.vehicle.wheelbase, sim::componentSeed(sc.seed, "odometry"));
  sim::MagneticRuler ruler(sc.magruler, map, sim::componentSeed(sc.seed, "magruler"));

  lcm::LogFile log(path, "w");
  if (!log.good()) throw std::runtime_error("cannot create log '" + path + "'");
  std::vector<uint8_t> buf;
  auto write = [&](const std::string& channel, const auto& msg) {
    buf.resize(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent ev;
    ev.eventnum = 0;
    ev.timestamp = msg.utime;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(buf.size());
    ev.data = buf.data();
    if (log.writeEvent(&ev) != 0) throw std::runtime_error("cannot write log '" + path + "'");
  };
  const std::string ruler_channel = channels.magruler.empty() ? "MAGRULER" : channels.magruler.front();
  int64_t odo_seq = 0, ruler_seq = 0;
  auto process = [&](const sim::TruthState& t) {
    if (auto o = odometry.sample(t)) {
      write(channels.odometry, drivers::toLcm(*o, odo_seq++));
      ++st.odometry;
      if (st.first_utime == 0) st.first_utime = o->input.utime;
      st.last_utime = o->input.utime;
    }
    if (auto r = ruler.sample(t)) {
      write(ruler_channel, drivers::toLcm(*r, ruler_seq++));
      if (r->detected) ++st.detections;
    }
    st.distance_m = t.distance;
  };
  process(vehicle.state());
  constexpr int64_t kProgressUs = 10000000;
  int64_t next_progress = sc.vehicle.start_utime + kProgressUs;
  while (!vehicle.finished() && vehicle.state().utime < end_utime) {
    process(vehicle.step());
    if (progress && vehicle.state().utime >= next_progress) {
      next_progress += kProgressUs;
      const double done = static_cast<double>(vehicle.state().utime - sc.vehicle.start_utime) /
                          static_cast<double>(end_utime - sc.vehicle.start_utime);
      if (!progress(done)) {
        st.stopped = true;
        break;
      }
    }
  }
  return st;
}

}  // namespace lcmloc::replay
