#include "lcmloc/fit/noise_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include <spdlog/fmt/fmt.h>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/scoring.hpp"
#include "lcmloc/core/vehicle_model.hpp"

namespace lcmloc::fit {
namespace {

/// The truth at utime (eval::interpolateTruth), or nullopt outside it or in a gap.
std::optional<TruthSample> truthAt(const std::vector<TruthSample>& t, int64_t utime, int64_t max_gap_us) {
  return eval::interpolateTruth(t, utime, max_gap_us);
}

/// The map by id (a map of a city has millions of entries: no search per observation).
std::unordered_map<int, const core::Marker*> byId(const core::MarkerMap& map) {
  std::unordered_map<int, const core::Marker*> ids;
  ids.reserve(map.size());
  for (const auto& m : map) ids.emplace(m.id, &m);
  return ids;
}

/// Range and bearing from the truth pose to (x, y).
void rangeBearing(const TruthSample& p, double x, double y, double& range, double& bearing) {
  const double dx = x - p.x, dy = y - p.y;
  range = std::hypot(dx, dy);
  bearing = core::wrapAngle(std::atan2(dy, dx) - p.heading);
}

/// Weighted least squares of e2 ~ a s + b r with a, b >= 0 (weights w; empty: all 1).
std::pair<double, double> fitTwoWeighted(const std::vector<double>& e2, const std::vector<double>& s,
                                         const std::vector<double>& r, const std::vector<double>& w) {
  double ss = 0, sr = 0, rr = 0, se = 0, re = 0;
  for (std::size_t i = 0; i < e2.size(); ++i) {
    const double wi = w.empty() ? 1.0 : w[i];
    ss += wi * s[i] * s[i];
    sr += wi * s[i] * r[i];
    rr += wi * r[i] * r[i];
    se += wi * s[i] * e2[i];
    re += wi * r[i] * e2[i];
  }
  const double det = ss * rr - sr * sr;
  double a = det > 0 ? (se * rr - re * sr) / det : -1, b = det > 0 ? (re * ss - se * sr) / det : -1;
  if (a < 0 || b < 0) {  // one term alone: the better of the two
    const double a1 = ss > 0 ? std::max(0.0, se / ss) : 0, b1 = rr > 0 ? std::max(0.0, re / rr) : 0;
    double ra = 0, rb = 0;
    for (std::size_t i = 0; i < e2.size(); ++i) {
      const double wi = w.empty() ? 1.0 : w[i];
      ra += wi * std::pow(e2[i] - a1 * s[i], 2);
      rb += wi * std::pow(e2[i] - b1 * r[i], 2);
    }
    a = ra <= rb ? a1 : 0;
    b = ra <= rb ? 0 : b1;
  }
  return {a, b};
}

/// One window of odometry from index i: the messages after i, each handed to step(o) until it
/// returns true (the window ends at that one: `whole`), unless two in a row are more than
/// max_odo_gap apart or the odometry ends first. `end`: the index the next window starts from.
struct OdometryWindow {
  std::size_t end = 0;
  bool whole = false;
};
template <typename Step>
OdometryWindow walkWindow(const std::vector<core::OdometryInput>& odo, std::size_t i, int64_t max_odo_gap, Step&& step) {
  for (std::size_t j = i + 1; j < odo.size(); ++j) {
    if (odo[j].utime - odo[j - 1].utime > max_odo_gap) return {j, false};
    if (step(odo[j])) return {j, true};
  }
  return {odo.size(), false};
}

/// The truth's heading at utime, or its direction of travel when it has none (over the shortest
/// interval around utime in which it moved min_move metres, at most 2 s each side).
std::optional<double> truthHeading(const std::vector<TruthSample>& t, int64_t utime, int64_t max_gap,
                                   double min_move = 0.05) {
  const auto p = truthAt(t, utime, max_gap);
  if (!p) return std::nullopt;
  if (p->has_heading) return p->heading;
  for (int64_t dt = 50000; dt <= 2000000; dt += 50000) {
    const auto a = truthAt(t, utime - dt, max_gap), b = truthAt(t, utime + dt, max_gap);
    if (!a || !b) return std::nullopt;
    if (std::hypot(b->x - a->x, b->y - a->y) >= min_move) return std::atan2(b->y - a->y, b->x - a->x);
  }
  return std::nullopt;
}

/// Least squares y = c x through the origin: c and its standard error.
NoiseFit::Scale throughOrigin(const std::vector<double>& x, const std::vector<double>& y) {
  NoiseFit::Scale s;
  s.n = static_cast<int64_t>(x.size());
  double xx = 0, xy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    xx += x[i] * x[i];
    xy += x[i] * y[i];
  }
  if (xx <= 0 || s.n < 2) return s;
  s.ratio = xy / xx;
  double rss = 0;
  for (std::size_t i = 0; i < x.size(); ++i) rss += std::pow(y[i] - s.ratio * x[i], 2);
  s.se = std::sqrt(rss / static_cast<double>(s.n - 1) / xx);
  return s;
}

/// NoiseFit::odometry_lag: windows of about 1 s of odometry, one every 0.25 s; at each lag L the
/// odometry's turn over [t0, t1] against the truth's heading change over [t0 + L, t1 + L], the
/// odometry scaled by least squares. A 50 ms grid over +-1 s, then 10 ms around its best.
void fitOdometryLag(const Recording& r, const FitOptions& opt, NoiseFit& f) {
  const int64_t max_gap = static_cast<int64_t>(opt.max_truth_gap_s * 1e6);
  const int64_t max_odo_gap = static_cast<int64_t>(opt.max_odometry_gap_s * 1e6);
  struct Window {
    int64_t t0, t1;
    double turn;
  };
  std::vector<Window> windows;
  int64_t next = INT64_MIN;
  for (std::size_t i = 0; i + 1 < r.odometry.size(); ++i) {
    if (r.odometry[i].utime < next) continue;
    double turn = 0;
    const auto w = walkWindow(r.odometry, i, max_odo_gap, [&](const core::OdometryInput& o) {
      turn += core::headingIncrement(o, r.wheelbase);
      return o.utime - r.odometry[i].utime >= 1000000;
    });
    if (!w.whole) continue;
    windows.push_back({r.odometry[i].utime, r.odometry[w.end].utime, turn});
    next = r.odometry[i].utime + 250000;
  }
  if (windows.size() < 50) return;
  // RMS at lag L [us] over the windows with the truth's heading at both ends (n: how many;
  // truth_rms: the RMS of the truth's heading change over them).
  auto rmsAt = [&](int64_t lag, int64_t* n, double* truth_rms = nullptr) {
    std::vector<double> a, b;
    for (const Window& w : windows) {
      const auto h0 = truthHeading(r.truth, w.t0 + lag, max_gap), h1 = truthHeading(r.truth, w.t1 + lag, max_gap);
      if (!h0 || !h1) continue;
      a.push_back(w.turn);
      b.push_back(core::wrapAngle(*h1 - *h0));
    }
    *n = static_cast<int64_t>(a.size());
    if (a.size() < 50) return std::numeric_limits<double>::infinity();
    const double k = throughOrigin(a, b).ratio;
    double ss = 0;
    double bb = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      ss += std::pow(k * a[i] - b[i], 2);
      bb += b[i] * b[i];
    }
    if (truth_rms) *truth_rms = std::sqrt(bb / static_cast<double>(a.size()));
    return std::sqrt(ss / static_cast<double>(a.size()));
  };
  NoiseFit::Lag lag;
  int64_t n0 = 0;
  lag.rms_at_zero = rmsAt(0, &n0);
  if (!std::isfinite(lag.rms_at_zero)) return;
  int64_t best = 0;
  double best_rms = lag.rms_at_zero;
  auto search = [&](int64_t from, int64_t to, int64_t step) {
    for (int64_t l = from; l <= to; l += step) {
      int64_t n = 0;
      const double v = rmsAt(l, &n);
      if (v < best_rms) {
        best_rms = v;
        best = l;
      }
    }
  };
  search(-1000000, 1000000, 50000);
  search(best - 40000, best + 40000, 10000);
  lag.seconds = static_cast<double>(best) * 1e-6;
  lag.rms = best_rms;
  rmsAt(best, &lag.n, &lag.truth_rms);
  f.odometry_lag = lag;
}

/// The odometry's distance and turn scales against the truth over windows of about 1 s.
void fitScales(const Recording& r, const FitOptions& opt, NoiseFit& f) {
  const int64_t max_gap = static_cast<int64_t>(opt.max_truth_gap_s * 1e6);
  const int64_t max_odo_gap = static_cast<int64_t>(opt.max_odometry_gap_s * 1e6);
  std::vector<double> ds_odo, ds_truth, dth_odo, dth_truth;
  std::size_t i = 0;
  while (i + 1 < r.odometry.size()) {
    double s = 0, turned = 0;
    const auto w = walkWindow(r.odometry, i, max_odo_gap, [&](const core::OdometryInput& o) {
      s += o.delta_s;
      turned += core::headingIncrement(o, r.wheelbase);
      return o.utime - r.odometry[i].utime >= 1000000;
    });
    const std::size_t j = w.end;
    if (!w.whole) {
      i = j;
      continue;
    }
    const int64_t ta = r.odometry[i].utime, tb = r.odometry[j].utime;
    const auto a = truthAt(r.truth, ta, max_gap), b = truthAt(r.truth, tb, max_gap);
    if (a && b && std::fabs(s) > 0.02) {  // a chord of about 1 s: the distance for a scale
      ds_odo.push_back(std::fabs(s));
      ds_truth.push_back(std::hypot(b->x - a->x, b->y - a->y));
    }
    const auto ha = truthHeading(r.truth, ta, max_gap), hb = truthHeading(r.truth, tb, max_gap);
    if (ha && hb && std::fabs(turned) > 0.1 && std::fabs(turned) < 2.5) {  // a turn, less than half a circle
      dth_odo.push_back(turned);
      dth_truth.push_back(core::wrapAngle(*hb - *ha));
    }
    i = j;
  }
  if (ds_odo.size() >= 5) f.odometry_scale = throughOrigin(ds_odo, ds_truth);
  if (dth_odo.size() >= 5) f.yaw_rate_scale = throughOrigin(dth_odo, dth_truth);
  else f.notes.push_back("yaw-rate scale: " + std::to_string(dth_odo.size()) + " windows that turn (5 needed): not fitted");
}

/// The odometry's error growth against the truth: dead reckoning from the truth's pose over
/// windows of pw_distance (or max_window_s) started at every message (overlapping: a short
/// recording has few disjoint ones), the odometry corrected by the scales fitted before where
/// they are significant (the filter's calibration states start there, so the process noise is
/// what is left after them). A truth without heading gives the start heading by its direction of
/// travel, and the heading's error only where the direction of travel is known at both ends.
void fitOdometry(const Recording& r, const FitOptions& opt, NoiseFit& f) {
  const double k_ds = f.odometry_scale && f.odometry_scale->significant() ? f.odometry_scale->ratio : 1.0;
  const double k_dth = f.yaw_rate_scale && f.yaw_rate_scale->significant() ? f.yaw_rate_scale->ratio : 1.0;
  const int64_t max_gap = static_cast<int64_t>(opt.max_truth_gap_s * 1e6);
  const int64_t max_odo_gap = static_cast<int64_t>(opt.max_odometry_gap_s * 1e6);
  const int64_t max_window = static_cast<int64_t>(opt.max_window_s * 1e6);
  std::vector<double> pos2, pos_dist, heading2, dist, turn;
  std::size_t i = 0;
  while (i + 1 < r.odometry.size()) {
    const auto start = truthAt(r.truth, r.odometry[i].utime, max_gap);
    const auto start_heading = start ? truthHeading(r.truth, r.odometry[i].utime, max_gap) : std::nullopt;
    if (!start_heading) {
      ++i;
      continue;
    }
    core::Pose p(start->x, start->y, *start_heading);
    double s = 0, turned = 0;
    const auto w = walkWindow(r.odometry, i, max_odo_gap, [&](const core::OdometryInput& o) {
      const double dth = k_dth * core::headingIncrement(o, r.wheelbase);
      p = core::propagatePose(p, k_ds * o.delta_s, dth);
      s += std::fabs(o.delta_s);
      turned += std::fabs(dth);
      return s >= r.pw_distance || o.utime - r.odometry[i].utime >= max_window;
    });
    const std::size_t j = w.end;
    if (!w.whole) {
      i = j;
      continue;
    }
    const auto end = truthAt(r.truth, r.odometry[j].utime, max_gap);
    if (end && (s > 0 || turned > 0)) {
      pos2.push_back(0.5 * (std::pow(end->x - p.x(), 2) + std::pow(end->y - p.y(), 2)));
      pos_dist.push_back(s / r.pw_distance);
      if (const auto end_heading = truthHeading(r.truth, r.odometry[j].utime, max_gap)) {
        heading2.push_back(std::pow(core::wrapAngle(*end_heading - p.z()), 2));
        dist.push_back(s / r.pw_distance);
        turn.push_back(turned);
      }
    }
    ++i;
  }
  f.odometry_windows = static_cast<int64_t>(pos2.size());
  if (pos2.size() < 10 || heading2.size() < 10) {
    f.notes.push_back(fmt::format("odometry: {} windows with the truth at both ends, {} with its heading (or direction of "
                                  "travel) at both (10 of each needed): process noise not fitted",
                                  pos2.size(), heading2.size()));
    return;
  }
  // Position: variance proportional to the distance (per pw_distance), fitted where the vehicle
  // moved; heading: per distance and per radian turned.
  double sum_e = 0, sum_s = 0;
  for (std::size_t k = 0; k < pos2.size(); ++k) {
    sum_e += pos2[k];
    sum_s += pos_dist[k];
  }
  const double q_pos = sum_s > 0 ? sum_e / sum_s : 0;
  const auto [q_heading, q_turn] = fitVarianceGrowth(heading2, dist, turn);
  f.pw_diag = core::Vec3(q_pos, q_pos, q_heading);
  f.pw_turn = q_turn;
}

}  // namespace

/// The heading's error growth per distance (a) and per radian turned (b), a, b >= 0: maximum
/// likelihood of the errors e (e2 = e^2) as zero-mean Gaussian with variance a s + b r. Fisher
/// scoring, which for a variance linear in its parameters is least squares of e2 weighted by
/// 1 / variance^2, repeated from the unweighted fit until it settles. (The unweighted fit alone
/// lets the few windows with the largest errors decide, and can put all the growth on one term.)
std::pair<double, double> fitVarianceGrowth(const std::vector<double>& e2, const std::vector<double>& s,
                                            const std::vector<double>& r) {
  auto [a, b] = fitTwoWeighted(e2, s, r, {});
  double mean = 0;
  for (double e : e2) mean += e / static_cast<double>(e2.size());
  const double floor = 1e-6 * mean;  // (a window that hardly moved must not take all the weight)
  std::vector<double> w(e2.size());
  for (int iter = 0; iter < 100 && (a > 0 || b > 0); ++iter) {
    for (std::size_t i = 0; i < e2.size(); ++i) w[i] = 1.0 / std::pow(std::max(a * s[i] + b * r[i], floor), 2);
    const auto [a2, b2] = fitTwoWeighted(e2, s, r, w);
    const bool settled = std::abs(a2 - a) <= 1e-6 * (a + b) && std::abs(b2 - b) <= 1e-6 * (a + b);
    a = a2;
    b = b2;
    if (settled) break;
  }
  return {a, b};
}


Residuals residualStats(std::vector<double> v) {
  Residuals r;
  r.n = static_cast<int64_t>(v.size());
  if (v.empty()) return r;
  r.median = core::percentile(v, 0.5);
  r.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  r.rms = core::rms(v);
  std::vector<double> dev;
  dev.reserve(v.size());
  for (double x : v) dev.push_back(std::fabs(x - r.median));
  r.sigma = 1.4826 * core::percentile(dev, 0.5);
  return r;
}

NoiseFit fitAgainstTruth(const Recording& r, const FitOptions& opt) {
  NoiseFit f;
  const int64_t max_gap = static_cast<int64_t>(opt.max_truth_gap_s * 1e6);
  if (r.truth.size() < 2) {
    f.notes.push_back("no ground truth: nothing fitted");
    return f;
  }
  const auto ids = byId(r.map);
  auto find = [&ids](int id) -> const core::Marker* {
    const auto it = ids.find(id);
    return it == ids.end() ? nullptr : it->second;
  };
  std::vector<double> range, bearing;
  // Each landmark's latest residual, for the correlation of successive ones.
  struct Last {
    int64_t utime;
    double range, bearing;
    bool has_bearing;
  };
  std::map<int, Last> last;
  std::vector<double> range_a, range_b, bearing_a, bearing_b;
  const auto max_pair_gap = static_cast<int64_t>(opt.max_pair_gap_s * 1e6);
  int64_t unknown = 0, not_in_map = 0;
  for (const auto& o : r.landmarks) {
    if (o.landmark_id < 0) {
      ++unknown;
      continue;
    }
    const core::Marker* m = find(o.landmark_id);
    const auto p = m ? truthAt(r.truth, o.utime, max_gap) : std::nullopt;
    if (!m) ++not_in_map;
    if (!p) continue;
    double rg, br;
    rangeBearing(*p, m->x, m->y, rg, br);
    range.push_back(o.range - rg);
    const double eb = core::wrapAngle(o.bearing - br);
    if (p->has_heading) bearing.push_back(eb);
    const auto prev = last.find(o.landmark_id);
    if (prev != last.end() && o.utime - prev->second.utime <= max_pair_gap && o.utime >= prev->second.utime) {
      range_a.push_back(prev->second.range);
      range_b.push_back(range.back());
      if (p->has_heading && prev->second.has_bearing) {
        bearing_a.push_back(prev->second.bearing);
        bearing_b.push_back(eb);
      }
    }
    last[o.landmark_id] = {o.utime, range.back(), eb, p->has_heading};
  }
  if (range_a.size() >= 30) {
    NoiseFit::Correlation c;
    c.pairs = static_cast<int64_t>(range_a.size());
    c.range_rho = correlation(range_a, range_b);
    if (bearing_a.size() >= 30) c.bearing_rho = correlation(bearing_a, bearing_b);
    const double rho = std::clamp(std::max(c.range_rho, c.bearing_rho), 0.0, 0.98);
    c.factor = (1.0 + rho) / (1.0 - rho);
    f.landmark_correlation = c;
  }
  if (!range.empty()) f.landmark_range = residualStats(range);
  if (!bearing.empty()) f.landmark_bearing = residualStats(bearing);
  if (unknown) f.notes.push_back(std::to_string(unknown) + " landmark observations without identity not used");
  if (not_in_map) f.notes.push_back(std::to_string(not_in_map) + " landmark observations of an id not in the map not used");
  if (!r.landmarks.empty() && bearing.empty() && !range.empty())
    f.notes.push_back("landmark bearing: the truth has no heading: not fitted");

  std::vector<double> beacon;
  std::map<int, std::vector<double>> by_id;
  for (const auto& b : r.beacons) {
    const core::Marker* m = find(b.beacon_id);
    const auto p = m ? truthAt(r.truth, b.utime, max_gap) : std::nullopt;
    if (!p) continue;
    const double e = b.range - std::hypot(m->x - p->x, m->y - p->y);
    beacon.push_back(e);
    by_id[b.beacon_id].push_back(e);
  }
  if (!beacon.empty()) f.beacon_range = residualStats(beacon);
  for (auto& [id, v] : by_id) f.beacon_range_by_id[id] = residualStats(std::move(v));
  if (f.beacon_range) {
    auto se = [](const Residuals& x) { return 1.2533 * x.sigma / std::sqrt(static_cast<double>(x.n)); };
    NoiseFit::RangeBias b;
    b.mean = f.beacon_range->median;
    b.std = std::max(0.05, 3.0 * se(*f.beacon_range));
    for (const auto& [id, x] : f.beacon_range_by_id) {
      if (x.n < 5) continue;
      ++b.of;
      b.beacons += std::fabs(x.median) > std::max(3.0 * se(x), 0.02);
      b.std = std::max(b.std, std::fabs(x.median - b.mean));
    }
    if (b.beacons > 0) f.beacon_bias = b;
  }

  std::vector<double> gps;
  for (const auto& g : r.gps) {
    if (!g.has_fix) continue;
    const auto p = truthAt(r.truth, g.utime, max_gap);
    if (!p) continue;
    gps.push_back(g.x - p->x);
    gps.push_back(g.y - p->y);
  }
  if (!gps.empty()) f.gps = residualStats(gps);

  if (!r.odometry.empty()) {
    fitOdometryLag(r, opt, f);
    if (f.odometry_lag && f.odometry_lag->significant()) {
      Recording moved = r;  // the odometry at the time of its motion
      const auto dt = static_cast<int64_t>(std::llround(f.odometry_lag->seconds * 1e6));
      for (auto& o : moved.odometry) o.utime += dt;
      fitScales(moved, opt, f);
      fitOdometry(moved, opt, f);
    } else {
      fitScales(r, opt, f);
      fitOdometry(r, opt, f);
    }
  }
  return f;
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  if (n < 2) return 0.0;
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= double(n);
  mb /= double(n);
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

std::string configFragment(const NoiseFit& f, double pw_distance) {
  std::ostringstream y;
  y << "# Noise fitted against the ground truth (lcmloc-fit-noise): the robust spread (1.4826 MAD)\n"
       "# of each sensor's residuals; the odometry's error growth per " << fmt::format("{}", pw_distance)
    << " m of travel and per radian turned.\n";
  y << "fusion:\n  filter:\n";
  if (f.pw_diag) {
    y << fmt::format("    pw_diag: [{:.6g}, {:.6g}, {:.6g}]   # {} odometry windows\n", (*f.pw_diag)[0],
                     (*f.pw_diag)[1], (*f.pw_diag)[2], f.odometry_windows);
    y << fmt::format("    pw_distance: {}\n", pw_distance);
    y << fmt::format("    pw_turn: {:.6g}\n", *f.pw_turn);
  }
  if (f.landmark_range || f.landmark_bearing || f.beacon_range) {
    y << "    landmarks:\n";
    if (f.landmark_range)
      y << fmt::format("      range_std: {:.6g}     # {} residuals, median {:.4g} m\n", f.landmark_range->sigma,
                       f.landmark_range->n, f.landmark_range->median);
    if (f.landmark_bearing)
      y << fmt::format("      bearing_std: {:.6g}   # {} residuals, median {:.4g} rad\n", f.landmark_bearing->sigma,
                       f.landmark_bearing->n, f.landmark_bearing->median);
    if (const auto& c = f.landmark_correlation)
      y << fmt::format("      correlation_factor: {:.4g}   # successive observations' residuals correlate {:.2f} (range), {:.2f} (bearing); {} pairs\n",
                       c->factor, c->range_rho, c->bearing_rho, c->pairs);
    if (f.beacon_range)
      y << fmt::format("      beacon_std: {:.6g}    # {} residuals of every beacon together (each one's median, its range bias, in the report)\n",
                       f.beacon_range->sigma, f.beacon_range->n);
  }
  if (f.gps) y << fmt::format("    gnss:\n      gps_std: {:.6g}   # {} axis residuals\n", f.gps->sigma, f.gps->n);
  return y.str();
}

}  // namespace lcmloc::fit
