// Physical magnetic ruler (paper §2.2): AMR sensors reading the vertical field of dipole
// markers, Earth field, a common-mode disturbance and white noise; peak mapping recovers d_m.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include "lcmloc/sim/world.hpp"
#include "lcmloc/sim/schedule.hpp"

namespace lcmloc::sim {
namespace {

constexpr double kMu0Over4Pi = 1e-7;   // [T m / A]
constexpr double kGaussPerTesla = 1e4;
constexpr double kCullDistance = 3.0;  // markers farther than this contribute < 1 mgauss [m]
constexpr int kBaselineExclusion = 4;  // sensors this close to the maximum are not baseline
constexpr double kBackgroundTau = 1.0;  // background tracking time constant [s]

double sensorLateralOf(const MagRulerConfig& cfg, int i) {
  return -0.5 * cfg.length + cfg.length * i / (cfg.num_sensors - 1);
}

/// Baseline-subtracted peak of a set of readings: index of the maximum, amplitude above the
/// baseline (mean of the sensors far from the maximum) and the parabola vertex in sensor-index
/// units (interpolated with the two neighbours).
struct RawPeak {
  int imax = 0;
  double amplitude = 0.0;
  double vertex = 0.0;
};

RawPeak rawPeak(const std::vector<double>& y) {
  const int n = static_cast<int>(y.size());
  RawPeak p;
  p.imax = static_cast<int>(std::max_element(y.begin(), y.end()) - y.begin());
  double sum = 0.0;
  int count = 0;
  for (int j = 0; j < n; ++j)
    if (std::abs(j - p.imax) > kBaselineExclusion) { sum += y[j]; ++count; }
  const double baseline = count > 0 ? sum / count : 0.0;
  p.amplitude = y[p.imax] - baseline;
  const int c = std::clamp(p.imax, 1, n - 2);
  const double denom = y[c - 1] - 2.0 * y[c] + y[c + 1];
  p.vertex = denom < 0.0 ? c + 0.5 * (y[c - 1] - y[c + 1]) / denom : p.imax;
  p.vertex = std::clamp(p.vertex, c - 1.0, c + 1.0);
  return p;
}

}  // namespace

double dipoleVerticalField(double moment, double rho, double dz) {
  const double r2 = rho * rho + dz * dz;
  const double r = std::sqrt(r2);
  const double cos2 = dz * dz / r2;
  return kMu0Over4Pi * moment * (3.0 * cos2 - 1.0) / (r2 * r) * kGaussPerTesla;
}

std::vector<double> singleMarkerReadings(const MagRulerConfig& cfg, double along, double lateral) {
  std::vector<double> out(cfg.num_sensors);
  const double dz = cfg.height + cfg.marker_depth;
  for (int i = 0; i < cfg.num_sensors; ++i) {
    const double rho = std::hypot(along, sensorLateralOf(cfg, i) - lateral);
    out[i] = cfg.earth_field_z + dipoleVerticalField(cfg.dipole_moment, rho, dz);
  }
  return out;
}

struct MagneticRuler::Impl {
  // Calibration: parabola vertex (sensor-index units) -> true lateral offset, increasing.
  std::vector<double> cal_vertex, cal_offset;
  double nominal_peak = 1.0;  // noise-free amplitude with the marker under the centre
  std::vector<double> gains;  // per-sensor sensitivity (1 + mismatch), drawn once

  // Disturbance process.
  double disturbance = 0.0;
  int64_t last_read_utime = 0;
  bool have_read = false;

  // Per-sensor background (Earth field through each sensor's own gain, slow disturbances),
  // tracked while no marker is near; detection works on readings minus background.
  std::vector<double> background;
  int64_t background_utime = 0;

  // Detection state.
  bool armed = true, tracking = false;
  double best_amplitude = 0.0;
  RulerReading best;
  int64_t next_raw_utime = 0;
  bool raw_started = false;

  // Markers by cell of a kCullDistance grid: a point's field needs only the markers of its own
  // and the eight neighbouring cells, so a read costs the same on a route of any length (a
  // linear scan of 20,000 markers for each of 13 sensors at 100 Hz took a whole core).
  // Keys may collide (cells far apart, or beyond the clamp): that only adds candidates, which the
  // distance test drops, and a marker found twice is taken once.
  std::unordered_map<uint64_t, std::vector<std::size_t>> cells;
  static int64_t cellOf(double v) {
    return static_cast<int64_t>(std::clamp(std::floor(v / kCullDistance), -1e15, 1e15));
  }
  static uint64_t key(int64_t ix, int64_t iy) {
    return static_cast<uint64_t>(ix) * 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(iy);
  }
};

MagneticRuler::MagneticRuler(const MagRulerConfig& cfg, const core::MarkerMap& markers,
                             uint64_t seed)
    : cfg_(cfg), markers_(markers), rng_(seed), impl_(std::make_shared<Impl>()) {
  if (cfg_.num_sensors < 3) throw std::invalid_argument("magruler.num_sensors: must be >= 3");
  if (!(cfg_.length > 0.0)) throw std::invalid_argument("magruler.length: must be > 0");
  if (!(cfg_.height + cfg_.marker_depth > 0.0))
    throw std::invalid_argument("magruler.height: sensor must be above the marker");
  // Peak mapping table from the noise-free model: sweep the true offset in 1 mm steps and keep
  // the monotonic branch through the centre.
  std::vector<double> v, d;
  for (int k = -700; k <= 700; ++k) {
    const double off = 1e-3 * k * cfg_.length;
    v.push_back(rawPeak(singleMarkerReadings(cfg_, 0.0, off)).vertex);
    d.push_back(off);
  }
  const auto mid = static_cast<int>(v.size() / 2);
  int lo = mid, hi = mid;
  while (lo > 0 && v[lo - 1] < v[lo]) --lo;
  while (hi + 1 < static_cast<int>(v.size()) && v[hi + 1] > v[hi]) ++hi;
  impl_->cal_vertex.assign(v.begin() + lo, v.begin() + hi + 1);
  impl_->cal_offset.assign(d.begin() + lo, d.begin() + hi + 1);
  impl_->nominal_peak = rawPeak(singleMarkerReadings(cfg_, 0.0, 0.0)).amplitude;
  std::normal_distribution<double> gain(1.0, cfg_.gain_std);
  for (int i = 0; i < cfg_.num_sensors; ++i) impl_->gains.push_back(gain(rng_));
  for (std::size_t k = 0; k < markers_.size(); ++k) {
    const auto& m = markers_[k];
    if (!std::isfinite(m.x) || !std::isfinite(m.y)) continue;  // no field anywhere (hypot is NaN or Inf)
    impl_->cells[Impl::key(Impl::cellOf(m.x), Impl::cellOf(m.y))].push_back(k);
  }
}

double MagneticRuler::sensorLateral(int i) const { return sensorLateralOf(cfg_, i); }

double MagneticRuler::fieldAt(double x, double y) const {
  const double dz = cfg_.height + cfg_.marker_depth;
  double b = cfg_.earth_field_z;
  if (!std::isfinite(x) || !std::isfinite(y)) return b;
  // The markers within reach, summed in map order (as a scan of the whole map would).
  thread_local std::vector<std::size_t> near;
  near.clear();
  const int64_t ix = Impl::cellOf(x), iy = Impl::cellOf(y);
  for (int64_t dx = -1; dx <= 1; ++dx)
    for (int64_t dy = -1; dy <= 1; ++dy)
      if (const auto it = impl_->cells.find(Impl::key(ix + dx, iy + dy)); it != impl_->cells.end())
        near.insert(near.end(), it->second.begin(), it->second.end());
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  for (const std::size_t k : near) {
    const auto& m = markers_[k];
    const double rho = std::hypot(x - m.x, y - m.y);
    if (rho < kCullDistance) b += dipoleVerticalField(cfg_.dipole_moment, rho, dz);
  }
  return b;
}

std::vector<double> MagneticRuler::read(const TruthState& truth) {
  // Common-mode disturbance: first-order Markov process in message time.
  std::normal_distribution<double> normal(0.0, 1.0);
  if (impl_->have_read && cfg_.disturbance_tau > 0.0) {
    const double dt = secondsBetween(truth.utime, impl_->last_read_utime);
    const double a = std::exp(-std::max(dt, 0.0) / cfg_.disturbance_tau);
    impl_->disturbance = a * impl_->disturbance +
                         std::sqrt(1.0 - a * a) * cfg_.disturbance_std * normal(rng_);
  } else if (!impl_->have_read) {
    impl_->disturbance = cfg_.disturbance_std * normal(rng_);
  }
  impl_->have_read = true;
  impl_->last_read_utime = truth.utime;

  const double c = std::cos(truth.heading), s = std::sin(truth.heading);
  const double cx = truth.x + cfg_.ruler_offset * c, cy = truth.y + cfg_.ruler_offset * s;
  std::vector<double> out(cfg_.num_sensors);
  for (int i = 0; i < cfg_.num_sensors; ++i) {
    const double lat = sensorLateral(i);
    out[i] = impl_->gains[i] * (fieldAt(cx - lat * s, cy + lat * c) + impl_->disturbance) +
             cfg_.noise_std * normal(rng_);
  }
  return out;
}

std::optional<double> MagneticRuler::peakMap(const std::vector<double>& readings,
                                             double* quality) const {
  if (static_cast<int>(readings.size()) != cfg_.num_sensors) return std::nullopt;
  const RawPeak p = rawPeak(readings);
  if (!(p.amplitude >= cfg_.detection_threshold)) return std::nullopt;
  const auto& cv = impl_->cal_vertex;
  const auto& co = impl_->cal_offset;
  double offset;
  if (p.vertex <= cv.front()) {
    offset = co.front();
  } else if (p.vertex >= cv.back()) {
    offset = co.back();
  } else {
    const auto k = static_cast<std::size_t>(std::upper_bound(cv.begin(), cv.end(), p.vertex) - cv.begin());
    const double t = (p.vertex - cv[k - 1]) / (cv[k] - cv[k - 1]);
    offset = co[k - 1] + t * (co[k] - co[k - 1]);
  }
  if (quality) {
    const bool edge = p.imax == 0 || p.imax == cfg_.num_sensors - 1;
    *quality = std::clamp(p.amplitude / impl_->nominal_peak, 0.0, 1.0) * (edge ? 0.5 : 1.0);
  }
  return offset;
}

std::optional<RulerReading> MagneticRuler::sample(const TruthState& truth) {
  Impl& st = *impl_;
  RulerReading now;
  now.utime = truth.utime;
  now.readings = read(truth);
  if (st.background.empty()) st.background = now.readings;
  std::vector<double> residual(now.readings.size());
  for (std::size_t i = 0; i < residual.size(); ++i) residual[i] = now.readings[i] - st.background[i];
  const double amplitude = rawPeak(residual).amplitude;
  if (!st.tracking && amplitude < 0.5 * cfg_.detection_threshold) {
    const double dt = secondsBetween(truth.utime, st.background_utime);
    const double w = std::clamp(dt / kBackgroundTau, 0.0, 1.0);
    for (std::size_t i = 0; i < residual.size(); ++i) st.background[i] += w * residual[i];
  }
  st.background_utime = truth.utime;

  std::optional<RulerReading> out;
  // The along-track maximum is confirmed once the amplitude has fallen clearly (well above the
  // noise) below the best sample's.
  const double fall_margin = 10.0 * cfg_.noise_std + 1e-3;
  if (st.tracking && amplitude < st.best_amplitude - fall_margin) {
    // The best sample is where the ruler crossed the marker.
    double q = 0.0;
    if (auto d = peakMap(st.best.readings, &q)) {
      out = st.best;
      out->detected = true;
      out->lateral_offset = *d;
      out->quality = q;
    }
    st.tracking = false;
    st.armed = false;
    st.best_amplitude = 0.0;
  } else if (st.armed && amplitude >= cfg_.detection_threshold &&
             amplitude > st.best_amplitude) {
    st.tracking = true;
    st.best_amplitude = amplitude;
    st.best = now;
  }
  if (!st.armed && !st.tracking && amplitude < 0.5 * cfg_.detection_threshold) st.armed = true;

  if (cfg_.publish_rate_hz > 0.0) {
    const auto period = static_cast<int64_t>(std::llround(1e6 / cfg_.publish_rate_hz));
    if (!st.raw_started) {
      st.raw_started = true;
      st.next_raw_utime = truth.utime;
    }
    if (scheduleDue(st.next_raw_utime, truth.utime, period) && !out) out = now;
  }
  return out;
}

}  // namespace lcmloc::sim
