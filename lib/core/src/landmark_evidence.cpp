#include "landmark_evidence.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/vehicle_model.hpp"

namespace lcmloc::core::detail {

void LandmarkEvidence::move(double ds, double dth) {
  if (seen_.empty()) return;  // nothing to carry
  dr_ = propagatePose(dr_, ds, dth);
}

std::optional<LandmarkEvidence::Found> LandmarkEvidence::add(int64_t utime, int id, double lx, double ly, double range,
                                                             double bearing, double range_std, double bearing_std,
                                                             double gate2) {
  if (seen_.empty()) dr_ = Pose::Zero();
  const double a = dr_.z() + bearing;
  Seen s;
  s.utime = utime;
  s.id = id;
  s.world = Vec2(lx, ly);
  s.dr = Vec2(dr_.x() + range * std::cos(a), dr_.y() + range * std::sin(a));
  s.var = range_std * range_std + range * range * bearing_std * bearing_std;
  seen_.push_back(s);
  while (seen_.size() > kMax || (seen_.size() > 1 && utime - seen_.front().utime > kMaxAgeUs)) seen_.pop_front();

  // Each pair of observations of two landmarks far enough apart gives the transform of the
  // dead-reckoned frame onto the map; the one most observations agree with is taken.
  std::optional<Found> best;
  for (std::size_t i = 0; i < seen_.size(); ++i)
    for (std::size_t j = i + 1; j < seen_.size(); ++j) {
      const Seen &p = seen_[i], &q = seen_[j];
      const Vec2 w = q.world - p.world, d = q.dr - p.dr;
      if (p.id == q.id || w.squaredNorm() < 4.0 * (p.var + q.var) || d.norm() < 1e-9) continue;
      const double rot = wrapAngle(std::atan2(w.y(), w.x()) - std::atan2(d.y(), d.x()));
      Mat2 R;
      R << std::cos(rot), -std::sin(rot), std::sin(rot), std::cos(rot);
      const Vec2 t = p.world - R * p.dr;
      int agree = 0;
      int64_t first = utime;
      double spread = 0, var = 0;
      std::vector<int> ids;
      for (const Seen& k : seen_) {
        const double e2 = (R * k.dr + t - k.world).squaredNorm();
        if (e2 > gate2 * (k.var + 0.5 * (p.var + q.var))) continue;
        ++agree;
        first = std::min(first, k.utime);
        spread = std::max(spread, std::sqrt(e2));
        var = std::max(var, k.var);
        if (std::find(ids.begin(), ids.end(), k.id) == ids.end()) ids.push_back(k.id);
      }
      // Enough of them, and most of what was refused: after a kidnapping every observation
      // agrees; among outliers a few may by chance, never most.
      if (agree < kAgree || 2 * static_cast<std::size_t>(agree) <= seen_.size() || ids.size() < 2 ||
          (best && agree <= best->observations))
        continue;
      Found f;
      f.pose.head<2>() = R * dr_.head<2>() + t;
      f.pose.z() = wrapAngle(dr_.z() + rot);
      const double heading_var = (p.var + q.var) / w.squaredNorm();
      f.P = Vec3(var, var, heading_var).asDiagonal();
      f.observations = agree;
      f.landmarks = static_cast<int>(ids.size());
      f.first_utime = first;
      f.spread = spread;
      best = f;
    }
  if (best) seen_.clear();
  return best;
}

}  // namespace lcmloc::core::detail
