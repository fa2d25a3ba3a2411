// Reference path made of constant-curvature segments, and the marker map laid along it.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::sim {
namespace {

/// Pose after travelling ds along an arc of curvature k from `start` (exact; ds may be < 0).
core::Pose advanceArc(const core::Pose& start, double k, double ds) {
  const double th = start.z();
  core::Pose p;
  if (std::abs(k) < 1e-12) {
    p << start.x() + ds * std::cos(th), start.y() + ds * std::sin(th), th;
  } else {
    const double th1 = th + k * ds;
    p << start.x() + (std::sin(th1) - std::sin(th)) / k,
        start.y() - (std::cos(th1) - std::cos(th)) / k, th1;
  }
  p.z() = core::wrapAngle(p.z());
  return p;
}

}  // namespace

Path::Path(const PathConfig& cfg) : cfg_(cfg) {
  if (cfg_.segments.empty()) throw std::invalid_argument("path.segments: at least one segment");
  core::Pose p(cfg_.x0, cfg_.y0, cfg_.theta0);
  double s = 0.0;
  for (const auto& seg : cfg_.segments) {
    if (!(seg.length > 0.0)) throw std::invalid_argument("path.segments.length: must be > 0");
    seg_start_.push_back(s);
    seg_pose_.push_back(p);
    p = advanceArc(p, seg.curvature, seg.length);
    s += seg.length;
  }
}

double Path::length() const { return seg_start_.back() + cfg_.segments.back().length; }

namespace {
// Index of the segment holding arc length s (first / last segment extended beyond the ends).
std::size_t segmentIndex(const std::vector<double>& starts, double s) {
  auto it = std::upper_bound(starts.begin(), starts.end(), s);
  return it == starts.begin() ? 0 : static_cast<std::size_t>(it - starts.begin() - 1);
}
}  // namespace

core::Pose Path::poseAt(double s) const {
  const std::size_t i = segmentIndex(seg_start_, s);
  return advanceArc(seg_pose_[i], cfg_.segments[i].curvature, s - seg_start_[i]);
}

double Path::curvatureAt(double s) const {
  return cfg_.segments[segmentIndex(seg_start_, s)].curvature;
}

double Path::project(double x, double y, double hint) const {
  // Coarse search around the hint, then a few Newton steps along the tangent.
  double best = hint, best_d2 = INFINITY;
  for (int i = -8; i <= 8; ++i) {
    const double s = hint + 0.25 * i;
    const core::Pose p = poseAt(s);
    const double d2 = (p.x() - x) * (p.x() - x) + (p.y() - y) * (p.y() - y);
    if (d2 < best_d2) { best_d2 = d2; best = s; }
  }
  for (int it = 0; it < 4; ++it) {
    const core::Pose p = poseAt(best);
    const double step = (x - p.x()) * std::cos(p.z()) + (y - p.y()) * std::sin(p.z());
    best += step;
    if (std::abs(step) < 1e-9) break;
  }
  return best;
}

core::MarkerMap makeMarkerMap(const Path& path, const MarkerLayout& layout) {
  core::MarkerMap map;
  for (int i = 0; i < layout.count; ++i) {
    const core::Pose p = path.poseAt(layout.first_at + i * layout.spacing);
    map.push_back(core::Marker{i, p.x(), p.y()});
  }
  return map;
}

}  // namespace lcmloc::sim
