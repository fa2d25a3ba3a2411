#include "lcmloc/core/landmark_fix.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "lcmloc/core/angles.hpp"

namespace lcmloc::core::landmark {

double predictBearing(const Vec2& p, double psi, const Vec2& lm) {
  const Vec2 d = lm - p;
  return wrapAngle(std::atan2(d.x(), d.y()) - psi);
}

Eigen::Matrix3d bearingJacobian(const Vec2& p, const std::vector<Vec2>& lms) {
  Eigen::Matrix3d J;
  for (int i = 0; i < 3; ++i) {
    const Vec2 d = lms[i] - p;
    const double r2 = d.squaredNorm();
    // az = atan2(dx, dy); d az/d px = -dy/r2, d az/d py = dx/r2.
    J(i, 0) = -d.y() / r2;
    J(i, 1) = d.x() / r2;
    J(i, 2) = -1.0;
  }
  return J;
}

Eigen::Matrix3d cramerRao(const Vec2& p, const std::vector<Vec2>& lms, double sigma) {
  const Eigen::Matrix3d J = bearingJacobian(p, lms);
  return sigma * sigma * (J.transpose() * J).inverse();
}

namespace {

/// Condition number of the Jacobian with position columns scaled by the mean range (so the
/// number does not depend on the unit of length).
double scaledCondition(const Vec2& p, const std::vector<Vec2>& lms) {
  Eigen::Matrix3d J = bearingJacobian(p, lms);
  double rbar = 0.0;
  for (const auto& l : lms) rbar += (l - p).norm() / 3.0;
  J.col(0) *= rbar;
  J.col(1) *= rbar;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(J);
  const auto s = svd.singularValues();
  return s(2) > 0 ? s(0) / s(2) : INFINITY;
}

bool gather(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
            std::vector<Vec2>* lms, std::vector<double>* alphas, FixResult* r) {
  if (bearings.size() != 3) {
    r->error = "need exactly three bearings, got " + std::to_string(bearings.size());
    return false;
  }
  for (const auto& b : bearings) {
    auto it = map.find(b.landmark_id);
    if (it == map.end()) {
      r->error = "landmark " + std::to_string(b.landmark_id) + " is not in the map";
      return false;
    }
    if (!std::isfinite(b.alpha)) {
      r->error = "bearing to landmark " + std::to_string(b.landmark_id) + " is not finite";
      return false;
    }
    for (const auto& l : *lms)
      if ((l - it->second).norm() < 1e-6) {
        r->error = "landmark " + std::to_string(b.landmark_id) + " used twice";
        return false;
      }
    lms->push_back(it->second);
    alphas->push_back(b.alpha);
  }
  return true;
}

/// Checks the geometry at p and fills condition / covariance; false with a reason if refused.
bool checkGeometry(const Vec2& p, const std::vector<Vec2>& lms, const FixOptions& o, FixResult* r) {
  for (const auto& l : lms)
    if ((l - p).norm() < 1e-3) {
      r->error = "vehicle at a landmark";
      return false;
    }
  r->condition = scaledCondition(p, lms);
  if (!(r->condition <= o.max_condition)) {
    r->error = "ill-conditioned geometry (condition " + std::to_string(r->condition) +
               "): vehicle on or near the danger circle through the three landmarks";
    return false;
  }
  r->covariance = cramerRao(p, lms, o.sigma_bearing);
  return true;
}

/// gather() and checkGeometry() at a finite INS pose; false with r->error if the fix is refused.
bool prepare(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings, const Vec2& p_ins,
             double psi_ins, const FixOptions& o, std::vector<Vec2>* lms, std::vector<double>* alphas,
             FixResult* r) {
  if (!gather(map, bearings, lms, alphas, r)) return false;
  if (!std::isfinite(psi_ins) || !p_ins.allFinite()) {
    r->error = "INS pose is not finite";
    return false;
  }
  return checkGeometry(p_ins, *lms, o, r);
}

/// Least-squares point of the lines through lms[i] with azimuths az[i]; false if singular.
bool linesPoint(const std::vector<Vec2>& lms, const double* az, Vec2* p) {
  // Line i: n_i . p = n_i . L_i with normal n_i = (cos az, -sin az).
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Vec2 b = Vec2::Zero();
  for (int i = 0; i < 3; ++i) {
    const Vec2 n(std::cos(az[i]), -std::sin(az[i]));
    A += n * n.transpose();
    b += n * n.dot(lms[i]);
  }
  if (std::abs(A.determinant()) < 1e-12) return false;
  *p = A.ldlt().solve(b);
  return true;
}

/// Error-triangle size (sum of squared sides) for azimuths az; infinite if two lines are parallel.
double triangleSize(const std::vector<Vec2>& lms, const double* az) {
  Vec2 pts[3];
  for (int k = 0; k < 3; ++k) {
    const int i = k, j = (k + 1) % 3;
    const Vec2 di(std::sin(az[i]), std::cos(az[i])), dj(std::sin(az[j]), std::cos(az[j]));
    const double den = di.x() * dj.y() - di.y() * dj.x();
    if (std::abs(den) < 1e-12) return INFINITY;
    const Vec2 w = lms[j] - lms[i];
    const double t = (w.x() * dj.y() - w.y() * dj.x()) / den;
    pts[k] = lms[i] + t * di;
  }
  return (pts[0] - pts[1]).squaredNorm() + (pts[1] - pts[2]).squaredNorm() + (pts[2] - pts[0]).squaredNorm();
}

}  // namespace

FixResult triangleFix(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
                      const Vec2& p_ins, double psi_ins, const FixOptions& o) {
  FixResult r;
  std::vector<Vec2> lms;
  std::vector<double> al;
  if (!prepare(map, bearings, p_ins, psi_ins, o, &lms, &al, &r)) return r;
  auto cost = [&](double dpsi) {
    double az[3];
    for (int i = 0; i < 3; ++i) az[i] = psi_ins - dpsi + al[i];
    return triangleSize(lms, az);
  };
  // Coarse scan, then golden section in the best bracket.
  const int n = 200;
  const double h = 2.0 * o.search_half_width / n;
  int best = 0;
  double bestc = INFINITY;
  for (int k = 0; k <= n; ++k) {
    const double c = cost(-o.search_half_width + k * h);
    if (c < bestc) bestc = c, best = k;
  }
  double a = -o.search_half_width + (best - 1) * h, b = -o.search_half_width + (best + 1) * h;
  const double gr = 0.5 * (std::sqrt(5.0) - 1.0);
  double c1 = b - gr * (b - a), c2 = a + gr * (b - a);
  double f1 = cost(c1), f2 = cost(c2);
  int it = 0;
  while (b - a > 1e-12 && it < 200) {
    ++it;
    if (f1 < f2) {
      b = c2, c2 = c1, f2 = f1, c1 = b - gr * (b - a), f1 = cost(c1);
    } else {
      a = c1, c1 = c2, f1 = f2, c2 = a + gr * (b - a), f2 = cost(c2);
    }
  }
  const double dpsi = 0.5 * (a + b);
  r.heading = wrapAngle(psi_ins - dpsi);
  r.triangle_size = cost(dpsi);
  r.iterations = it;
  double az[3];
  for (int i = 0; i < 3; ++i) az[i] = r.heading + al[i];
  if (!linesPoint(lms, az, &r.position)) {
    r.error = "azimuth lines are parallel";
    return r;
  }
  if (!checkGeometry(r.position, lms, o, &r)) return r;
  r.ok = true;
  return r;
}

namespace {
FixResult solveLs(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
                  const Vec2& p_ins, double psi_ins, const FixOptions& o, bool damped) {
  FixResult r;
  std::vector<Vec2> lms;
  std::vector<double> al;
  if (!prepare(map, bearings, p_ins, psi_ins, o, &lms, &al, &r)) return r;
  Eigen::Vector3d x(p_ins.x(), p_ins.y(), psi_ins);
  auto residual = [&](const Eigen::Vector3d& s) {
    Eigen::Vector3d e;
    for (int i = 0; i < 3; ++i) e(i) = wrapAngle(al[i] - predictBearing(s.head<2>(), s(2), lms[i]));
    return e;
  };
  double lambda = damped ? 1e-3 : 0.0;
  Eigen::Vector3d e = residual(x);
  double cost = e.squaredNorm();
  int it = 0;
  for (; it < o.max_iterations && cost > 1e-30; ++it) {
    const Eigen::Matrix3d J = bearingJacobian(x.head<2>(), lms);
    const Eigen::Matrix3d A = J.transpose() * J;
    const Eigen::Vector3d g = J.transpose() * e;
    bool stepped = false;
    for (int tries = 0; tries < 30; ++tries) {
      Eigen::Matrix3d Ad = A;
      Ad.diagonal() += lambda * A.diagonal();
      const Eigen::Vector3d dx = Ad.ldlt().solve(g);
      if (!dx.allFinite()) break;
      Eigen::Vector3d xn = x + dx;
      xn(2) = wrapAngle(xn(2));
      const Eigen::Vector3d en = residual(xn);
      const double cn = en.squaredNorm();
      if (!damped || cn < cost) {
        x = xn, e = en, cost = cn;
        lambda = std::max(lambda * 0.3, 1e-9);
        stepped = true;
        if (dx.head<2>().norm() < 1e-9 && std::abs(dx(2)) < 1e-13) it = o.max_iterations;
        break;
      }
      lambda *= 10.0;
    }
    if (!stepped) break;
    if (!x.allFinite()) break;
  }
  r.iterations = it;
  r.position = x.head<2>();
  r.heading = wrapAngle(x(2));
  if (!x.allFinite() || std::sqrt(cost / 3.0) > 10.0 * o.sigma_bearing + 1e-6) {
    r.error = "did not converge (rms bearing residual " + std::to_string(std::sqrt(cost / 3.0)) + " rad)";
    return r;
  }
  if (!checkGeometry(r.position, lms, o, &r)) return r;
  r.ok = true;
  return r;
}
}  // namespace

FixResult leastSquaresFix(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
                          const Vec2& p_ins, double psi_ins, const FixOptions& o) {
  return solveLs(map, bearings, p_ins, psi_ins, o, true);
}

FixResult gaussNewtonFix(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
                         const Vec2& p_ins, double psi_ins, const FixOptions& o) {
  return solveLs(map, bearings, p_ins, psi_ins, o, false);
}

}  // namespace lcmloc::core::landmark
