#include "lcmloc/fit/innovation_fit.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include <spdlog/fmt/fmt.h>

#include "lcmloc/core/chi2.hpp"
#include "lcmloc/core/engine.hpp"

namespace lcmloc::fit {
namespace {

/// The recording's inputs as the engine takes them, in time order (odometry first at equal
/// times, as the canonical order has it). Each channel's seq counts its messages.
std::vector<core::EngineInput> engineInputs(const Recording& r, const RecordingChannels& ch) {
  std::vector<core::EngineInput> in;
  in.reserve(r.odometry.size() + r.landmarks.size() + r.beacons.size() + r.gps.size());
  std::map<std::string, int64_t> seq;
  auto add = [&](const std::string& channel, int64_t utime, core::InputPayload p) {
    in.push_back(core::EngineInput{channel, seq[channel]++, utime, std::move(p)});
  };
  for (const auto& o : r.odometry) add(ch.odometry, o.utime, o);
  for (const auto& m : r.landmarks) add(m.sensor.empty() ? ch.landmarks : m.sensor, m.utime, m);
  for (const auto& m : r.beacons) add(m.sensor.empty() ? ch.beacons : m.sensor, m.utime, m);
  for (const auto& m : r.gps) add(m.sensor.empty() ? ch.gps : m.sensor, m.utime, m);
  std::stable_sort(in.begin(), in.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });
  return in;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

std::vector<SensorNis> runNis(const Recording& r, const core::EngineConfig& cfg, const RecordingChannels& ch) {
  struct Acc {
    int dof = 0;
    int64_t accepted = 0;
    std::vector<double> nis;
    double sum_norm = 0;
  };
  std::vector<std::string> order;
  std::map<std::string, Acc> acc;
  core::EngineOutputs out;
  out.on_decision = [&](const std::string&, bool is_active, const core::GateDecision& d) {
    if (!is_active || d.innovation.size() == 0 || !std::isfinite(d.mahalanobis)) return;
    auto [it, added] = acc.try_emplace(d.sensor);
    if (added) order.push_back(d.sensor);
    it->second.dof = std::max(it->second.dof, static_cast<int>(d.innovation.size()));
    it->second.nis.push_back(d.mahalanobis);
    it->second.sum_norm += d.innovation.norm();
    if (d.accepted) ++it->second.accepted;
  };
  core::EngineConfig c = cfg;
  c.shadow.clear();
  core::FusionEngine engine(c, r.map, out);
  for (auto& in : engineInputs(r, ch)) engine.push(std::move(in));
  engine.flush();

  std::vector<SensorNis> res;
  for (const auto& s : order) {
    const Acc& a = acc[s];
    SensorNis n;
    n.sensor = s;
    n.dof = std::clamp(a.dof, 1, 10);
    n.decided = static_cast<int64_t>(a.nis.size());
    n.accepted = a.accepted;
    double sum = 0;
    for (double v : a.nis) sum += v;
    n.mean = sum / static_cast<double>(n.decided);
    n.median = median(a.nis);
    n.mean_innovation = a.sum_norm / static_cast<double>(n.decided);
    n.expected_median = core::chi2Quantile(0.5, n.dof);
    // The mean of N NIS of dof each: chi-square of N dof degrees of freedom, divided by N.
    const double nd = static_cast<double>(n.decided) * n.dof;
    n.band_lo = core::chi2QuantileAnyDof(0.025, nd) / static_cast<double>(n.decided);
    n.band_hi = core::chi2QuantileAnyDof(0.975, nd) / static_cast<double>(n.decided);
    res.push_back(n);
  }
  return res;
}

const SensorNis* find(const std::vector<SensorNis>& v, const std::string& sensor) {
  for (const auto& n : v)
    if (n.sensor == sensor) return &n;
  return nullptr;
}

/// The sensors of one noise key: every channel of its kind in the recording.
template <typename T>
std::vector<std::string> channelsOf(const std::vector<T>& msgs, const std::string& fallback) {
  std::vector<std::string> ch;
  for (const auto& m : msgs) {
    const std::string& s = m.sensor.empty() ? fallback : m.sensor;
    if (std::find(ch.begin(), ch.end(), s) == ch.end()) ch.push_back(s);
  }
  return ch;
}

}  // namespace

std::vector<SensorNis> nisPerSensor(const Recording& r, const core::EngineConfig& cfg, const RecordingChannels& ch) {
  return runNis(r, cfg, ch);
}

InnovationFit fitByInnovations(const Recording& r, core::EngineConfig cfg, const InnovationFitOptions& opt) {
  InnovationFit f;
  struct Key {
    std::string name;
    std::vector<std::string> sensors;
    std::vector<double*> sigmas;  ///< scaled together
    bool active = true;
    std::vector<double> start;  ///< the sigmas as configured
    bool floor = false;  ///< shrunk 100x and the NIS still below its median
  };
  std::vector<Key> keys;
  core::FilterConfig& fc = cfg.filter;
  int64_t rows_with_sigma = 0;
  for (const auto& m : r.landmarks) rows_with_sigma += m.range_std > 0 || m.bearing_std > 0;
  keys.push_back({"landmarks.range_std, landmarks.bearing_std", channelsOf(r.landmarks, opt.channels.landmarks),
                  {&fc.landmarks.range_std, &fc.landmarks.bearing_std}, true, {}, false});
  if (rows_with_sigma > 0) {
    keys.back().active = false;
    f.notes.push_back(fmt::format("{} landmark rows carry their own sigma: landmarks.range_std and bearing_std not fitted",
                                  rows_with_sigma));
  }
  rows_with_sigma = 0;
  for (const auto& m : r.beacons) rows_with_sigma += m.range_std > 0;
  keys.push_back({"landmarks.beacon_std", channelsOf(r.beacons, opt.channels.beacons), {&fc.landmarks.beacon_std}, true, {}, false});
  if (rows_with_sigma > 0) {
    keys.back().active = false;
    f.notes.push_back(fmt::format("{} beacon rows carry their own sigma: landmarks.beacon_std not fitted", rows_with_sigma));
  }
  rows_with_sigma = 0;
  for (const auto& m : r.gps) rows_with_sigma += m.has_fix && m.position_std > 0;
  keys.push_back({"gnss.gps_std", channelsOf(r.gps, opt.channels.gps), {&fc.gnss.gps_std}, true, {}, false});
  if (rows_with_sigma > 0) {
    keys.back().active = false;
    f.notes.push_back(fmt::format("{} fixes carry their own sigma: gnss.gps_std not fitted", rows_with_sigma));
  }

  // Every run of the filter over the recording, counted.
  auto run = [&] {
    ++f.runs;
    return runNis(r, cfg, opt.channels);
  };
  f.before = run();
  std::vector<SensorNis> now = f.before;
  // The GNSS filters' position process noise: the one that predicts the fixes best.
  const Key& gps_key = keys.back();
  if (opt.position_rw && core::isGnssFilter(fc.type) && gps_key.active && !gps_key.sensors.empty() &&
      fc.gnss.position_rw > 0) {
    auto prediction_error = [&](const std::vector<SensorNis>& nis, int64_t& n) {
      double sum = 0;
      n = 0;
      for (const auto& sensor : gps_key.sensors)
        if (const SensorNis* x = find(nis, sensor)) {
          sum += x->mean_innovation * static_cast<double>(x->decided);
          n += x->decided;
        }
      return n > 0 ? sum / static_cast<double>(n) : 0.0;
    };
    int64_t n = 0;
    const double start = fc.gnss.position_rw, err0 = prediction_error(f.before, n);
    if (n >= opt.min_decisions) {
      double best = start, best_err = err0;
      int best_k = 0;
      for (int k = -4; k <= 12; ++k) {
        if (k == 0) continue;
        fc.gnss.position_rw = start * std::pow(2.0, 0.5 * k);
        const double e = prediction_error(run(), n);
        if (e < best_err) {
          best = fc.gnss.position_rw;
          best_err = e;
          best_k = k;
        }
      }
      fc.gnss.position_rw = best;
      f.rw_error = {err0, best_err};
      if (best_k != 0) f.fitted.push_back("gnss.position_rw");
      if (best_k == -4 || best_k == 12)
        f.notes.push_back(fmt::format("gnss.position_rw: the best of the grid is at its edge ({:.4g}, {:+.1f} octaves)",
                                      best, 0.5 * best_k));
      if (best_k != 0) now = run();
    }
  }
  for (auto& k : keys)
    for (double* s : k.sigmas) k.start.push_back(*s);
  for (f.iterations = 0; f.iterations < opt.max_iterations; ++f.iterations) {
    bool changed = false;
    for (auto& k : keys) {
      if (!k.active || k.sensors.empty()) continue;
      double num = 0, den = 0;  // the decisions of all its sensors, weighted by count
      int64_t n = 0;
      for (const auto& s : k.sensors)
        if (const SensorNis* x = find(now, s)) {
          num += x->median * static_cast<double>(x->decided);
          den += x->expected_median * static_cast<double>(x->decided);
          n += x->decided;
        }
      if (n < opt.min_decisions || den <= 0) continue;
      const double ratio = num / den;  // NIS about proportional to R when R dominates S
      if (std::abs(ratio - 1.0) <= opt.tolerance) continue;
      // A step on the sigma of sqrt(ratio), bounded so that one iteration moves it by at most 4x.
      const double step = std::clamp(std::sqrt(ratio), 0.25, 4.0);
      for (double* s : k.sigmas) *s *= step;
      if (*k.sigmas.front() < 0.01 * k.start.front()) {  // the sigma cannot explain the NIS: kept as it was
        k.floor = true;
        k.active = false;
        for (std::size_t i = 0; i < k.sigmas.size(); ++i) *k.sigmas[i] = k.start[i];
      }
      changed = true;
    }
    if (!changed) break;
    now = run();
  }
  for (const auto& k : keys) {
    if (k.sensors.empty() || (!k.active && !k.floor)) continue;
    int64_t n = 0;
    for (const auto& s : k.sensors)
      if (const SensorNis* x = find(now, s)) n += x->decided;
    if (k.floor)
      f.notes.push_back(k.name + ": the NIS stayed below its median with the sigma shrunk 100-fold: the "
                                 "prediction's own uncertainty explains the innovations (process noise too large?); not fitted");
    else if (n < opt.min_decisions)
      f.notes.push_back(fmt::format("{}: {} decisions with a candidate, fewer than {}: not fitted", k.name, n,
                                    opt.min_decisions));
    else
      f.fitted.push_back(k.name);
  }
  if (f.iterations == opt.max_iterations)
    f.notes.push_back(fmt::format("the scaling had not settled after {} runs", opt.max_iterations));
  f.after = now;
  f.filter = fc;
  return f;
}

std::string configFragment(const InnovationFit& f) {
  std::ostringstream y;
  y << "# Measurement noise fitted to the innovations (lcmloc-fit-noise --innovations): each sensor's\n"
       "# sigma scaled until the median NIS equals the chi-square median of its dof.\n";
  y << "fusion:\n  filter:\n";
  auto has = [&](const char* k) { return std::find(f.fitted.begin(), f.fitted.end(), k) != f.fitted.end(); };
  const bool lm = has("landmarks.range_std, landmarks.bearing_std"), bc = has("landmarks.beacon_std");
  if (lm || bc) y << "    landmarks:\n";
  if (lm)
    y << fmt::format("      range_std: {:.6g}\n      bearing_std: {:.6g}\n", f.filter.landmarks.range_std,
                     f.filter.landmarks.bearing_std);
  if (bc) y << fmt::format("      beacon_std: {:.6g}\n", f.filter.landmarks.beacon_std);
  const bool gs = has("gnss.gps_std"), rw = has("gnss.position_rw");
  if (gs || rw) y << "    gnss:\n";
  if (gs) y << fmt::format("      gps_std: {:.6g}\n", f.filter.gnss.gps_std);
  if (rw)
    y << fmt::format("      position_rw: {:.6g}   # mean GPS prediction error {:.3g} m (was {:.3g} m)\n",
                     f.filter.gnss.position_rw, f.rw_error.second, f.rw_error.first);
  return y.str();
}

core::FilterConfig withFit(core::FilterConfig cfg, const NoiseFit& f, double pw_distance) {
  if (f.pw_diag) {
    cfg.pw_diag = *f.pw_diag;
    cfg.pw_distance = pw_distance;
  }
  if (f.pw_turn) cfg.pw_turn = *f.pw_turn;
  if (f.landmark_range) cfg.landmarks.range_std = f.landmark_range->sigma;
  if (f.landmark_bearing) cfg.landmarks.bearing_std = f.landmark_bearing->sigma;
  if (f.landmark_correlation) cfg.landmarks.correlation_factor = f.landmark_correlation->factor;
  if (f.beacon_range) cfg.landmarks.beacon_std = f.beacon_range->sigma;
  if (f.gps) cfg.gnss.gps_std = f.gps->sigma;
  return cfg;
}

std::string nisTable(const std::vector<SensorNis>& nis) {
  std::string s = fmt::format("{:<18} {:>4} {:>9} {:>9} {:>9} {:>9} {:>19}  {}\n", "NIS sensor", "dof", "decided",
                              "accepted", "median", "mean", "95 % band of mean", "");
  for (const auto& n : nis)
    s += fmt::format("{:<18} {:>4} {:>9} {:>9} {:>9.3g} {:>9.3g} {:>9.3g} .. {:<6.3g}  {}\n", n.sensor, n.dof, n.decided,
                     n.accepted, n.median, n.mean, n.band_lo, n.band_hi,
                     n.consistent() ? "consistent" : (n.mean > n.band_hi ? "too large" : "too small"));
  return s;
}

}  // namespace lcmloc::fit
