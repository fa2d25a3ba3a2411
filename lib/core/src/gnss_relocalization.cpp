// Re-localization of the GNSS filters from the GPS fixes their gate refused (docs/tvekf.md,
// "Re-localization"): a window of refused fixes carried forward by the dead-reckoned motion,
// and the pose taken from them once several agree with each other and none with the estimate.
#include <algorithm>
#include <cmath>
#include <limits>

#include "gnss_filter_base.hpp"
#include "lcmloc/core/angles.hpp"

namespace lcmloc::core::gnss_filter {

void RejectedFixes::move(double ds, double theta, double step_heading_var) {
  dr_ += ds * Vec2(std::cos(theta), std::sin(theta));
  hvar_ += step_heading_var;
}

RejectedFixes::Agreement RejectedFixes::add(int64_t utime, const Vec2& z, double sd, double heading_var,
                                            double gate) {
  // A fix not newer than the window's newest is not independent of it: it replaces what it follows.
  while (!w_.empty() && w_.back().utime >= utime) w_.pop_back();
  const auto max_age = static_cast<int64_t>(kMaxAgeS * 1e6);
  while (!w_.empty() && utime - w_.front().utime > max_age) w_.pop_front();
  w_.push_back({utime, z, sd * sd, dr_, hvar_});
  if (w_.size() > kCapacity) w_.pop_front();
  Agreement best = agreeing(w_.size(), heading_var, gate);
  const Fix& n = w_.back();
  for (std::size_t i = 0; i + 1 < w_.size(); ++i) {
    const double s = kChordSigmas * std::sqrt(w_[i].var + n.var);
    if ((n.z - w_[i].z).norm() < s || (n.dr - w_[i].dr).norm() < s) continue;
    const Agreement a = agreeing(i, heading_var, gate);
    if (a.fixes > best.fixes || (a.fixes == best.fixes && a.heading && a.heading_var < best.heading_var)) best = a;
  }
  return best;
}

RejectedFixes::Agreement RejectedFixes::agreeing(std::size_t anchor, double heading_var, double gate) const {
  const Fix& n = w_.back();
  Agreement r;
  r.first_utime = n.utime;
  double rot_var = heading_var;  // the heading error the carrying forward may have
  if (anchor < w_.size()) {
    const Fix& a = w_[anchor];
    const Vec2 c = n.z - a.z, d = n.dr - a.dr;
    r.heading = true;
    r.dtheta = wrapAngle(std::atan2(c.y(), c.x()) - std::atan2(d.y(), d.x()));
    rot_var = (a.var + n.var) / c.squaredNorm() + (n.hvar - a.hvar);
    r.heading_var = rot_var;
  }
  const double c = std::cos(r.dtheta), s = std::sin(r.dtheta);
  Mat2 R;
  R << c, -s, s, c;
  double bound = std::numeric_limits<double>::infinity();  // heading variance the agreement bounds
  for (std::size_t i = 0; i + 1 < w_.size(); ++i) {
    const Fix& f = w_[i];
    const Vec2 d = n.dr - f.dr;
    const Vec2 e = n.z - (f.z + R * d);
    const double var = f.var + n.var + (rot_var + n.hvar - f.hvar) * d.squaredNorm();
    if (!(e.squaredNorm() <= gate * var)) {
      if (i == anchor) return Agreement{};  // the chord's own fix does not agree: no heading from it
      continue;
    }
    ++r.fixes;
    r.first_utime = std::min(r.first_utime, f.utime);
    r.spread = std::max(r.spread, e.norm());
    if (d.squaredNorm() > 0) bound = std::min(bound, (f.var + n.var) / d.squaredNorm() + (n.hvar - f.hvar));
  }
  // Heading kept: the fixes agreed with it to within what their dead-reckoned chord can tell.
  if (!r.heading) r.heading_var = std::max(heading_var, bound);
  return r;
}

void GnssFilterBase::refusedFix(const GpsInput& gps, const Vec2& z, double sd, GateDecision& d) {
  Eigen::VectorXd x;
  Eigen::MatrixXd P;
  fillState(x, P);
  // Until a fix confirmed it, the state is a prior: its heading is not evidence either.
  const double max_var = kLockoutMaxHeadingStd * kLockoutMaxHeadingStd;
  const double heading_var = confirmed_ ? P(kTheta, kTheta) : std::max(P(kTheta, kTheta), max_var);
  const RejectedFixes::Agreement a = rejected_.add(gps.utime, z, sd, heading_var, gate2_);
  if (a.fixes >= (confirmed_ ? 3 : 2)) {
    relocalize(z, sd, a, gps.utime);
    d.accepted = true;
    d.reason = "relocalized";
    return;
  }
  gps_lock_.reject();  // status LOCKOUT after gnss.gps_lockout_rejections in a row; no inflation
}

void GnssFilterBase::relocalize(const Vec2& z, double sd, const RejectedFixes::Agreement& a, int64_t utime) {
  Eigen::VectorXd x;
  Eigen::MatrixXd P;
  fillState(x, P);
  Relocalization r;
  r.utime = utime;
  r.fixes = a.fixes;
  r.first_utime = a.first_utime;
  r.spread = a.spread;
  r.jump = (z - x.head<2>()).norm();
  const double kept_heading_var = P(kTheta, kTheta);
  x.head<2>() = z;
  for (int i : {kX, kY, kTheta}) {
    P.row(i).setZero();
    P.col(i).setZero();
  }
  P(kX, kX) = P(kY, kY) = sd * sd;
  const double max_var = kLockoutMaxHeadingStd * kLockoutMaxHeadingStd;
  if (a.heading) {
    x[kTheta] = wrapAngle(x[kTheta] + a.dtheta);
    P(kTheta, kTheta) = std::min(a.heading_var, max_var);
    r.heading_from_chord = true;
    r.heading_change = a.dtheta;
  } else {  // kept, its sigma opened to what the agreement bounds (at most 1 rad)
    P(kTheta, kTheta) = std::max(kept_heading_var, std::min(a.heading_var, max_var));
  }
  r.heading_std = std::sqrt(P(kTheta, kTheta));
  setState(x, P);
  rejected_.clear();
  gps_lock_.accept();
  confirmed_ = true;
  course_open_ = false;
  have_fix_ = true;
  last_fix_utime_ = utime;
  relocalized_ = r;
}

}  // namespace lcmloc::core::gnss_filter
