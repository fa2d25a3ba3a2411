#pragma once
// Composition of odometry increments for the batched time update (fusion.output_every > 1).
// The increments of eq. 1-2 (arc of length ds turning dtheta, midpoint heading) are composed
// in the body frame of the pose where the batch starts: dead reckoning from the origin. Moving
// a pose by the composed increment is, for the mean, exactly the same as moving it by each
// increment in turn (SE(2) composition; equal up to floating-point rounding).
//
// Process noise: each step adds q = (qx, qy, qtheta) (world frame, diagonal) after its motion.
// The heading noise of step k turns the rest of the batch's travel r_k (body frame) by a random
// angle, moving the end point by J r_k per radian (J: rotation by +90 deg). The batch keeps the
// moments of q_theta over the steps' end points d_k so that noise() returns, for the whole batch,
// sum_k G_k diag(q_k) G_k' with G_k the Jacobian of the remaining steps: the covariance the
// step-by-step linear propagation (dead reckoning) adds, exactly.
#include <cmath>
#include <cstdint>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/types.hpp"

namespace lcmloc::core {

struct OdometryBatch {
  double dx = 0.0, dy = 0.0;  ///< translation, body frame of the batch's start pose [m]
  double dtheta = 0.0;        ///< heading change (not wrapped) [rad]
  double distance = 0.0;      ///< sum of |ds| [m]
  int steps = 0;              ///< increments composed
  int64_t utime = 0;          ///< utime of the last increment
  Vec3 q_sum = Vec3::Zero();  ///< sum of the steps' process noise (qx, qy, qtheta)
  Vec2 m1 = Vec2::Zero();     ///< sum of qtheta_k d_k
  Mat2 m2 = Mat2::Zero();     ///< sum of qtheta_k d_k d_k' (upper triangle)
  double c_ = 1.0, s_ = 0.0;  ///< cos, sin of dtheta (by angle addition)

  /// Appends one increment (ds, dth) of eq. 1 taken at the end of the batch so far, followed by
  /// process noise q (diagonal, world frame).
  void add(double ds, double dth, int64_t t, const Vec3& q) {
    // cos, sin of the midpoint heading dtheta + dth / 2 by angle addition from those of dtheta
    // (no libm call per step for the usual small increments; see sinCosSmall).
    double sh, chh;
    sinCosSmall(0.5 * dth, sh, chh);
    const double cm = c_ * chh - s_ * sh, sm = s_ * chh + c_ * sh;
    dx += ds * cm;
    dy += ds * sm;
    c_ = cm * chh - sm * sh;  // advance by the second half
    s_ = sm * chh + cm * sh;
    dtheta += dth;
    distance += std::abs(ds);
    ++steps;
    utime = t;
    q_sum += q;
    const double qx = q.z() * dx, qy = q.z() * dy;
    m1.x() += qx;
    m1.y() += qy;
    m2(0, 0) += qx * dx;
    m2(0, 1) += qx * dy;
    m2(1, 1) += qy * dy;
  }
  /// |a| up to which sinCosSmall evaluates its polynomials [rad].
  static constexpr double kSmallAngle = 0.25;
  /// sin and cos of a: Taylor polynomials for |a| <= kSmallAngle, libm otherwise. To a^9 and
  /// a^10 for |a| <= 0.05 (the half increments of one odometry step), to a^13 and a^14 beyond:
  /// truncation error below 3e-21 relative either way, far under the rounding of the result.
  static void sinCosSmall(double a, double& s, double& c) {
    // 1/k! for the sine's odd and the cosine's even powers
    constexpr double k3 = 1.0 / 6, k5 = 1.0 / 120, k7 = 1.0 / 5040, k9 = 1.0 / 362880, k11 = 1.0 / 39916800,
                     k13 = 1.0 / 6227020800.0;
    constexpr double k2 = 1.0 / 2, k4 = 1.0 / 24, k6 = 1.0 / 720, k8 = 1.0 / 40320, k10 = 1.0 / 3628800,
                     k12 = 1.0 / 479001600, k14 = 1.0 / 87178291200.0;
    const double a2 = a * a;
    if (std::abs(a) <= 0.05) {
      s = a + a * a2 * (-k3 + a2 * (k5 + a2 * (-k7 + a2 * k9)));
      c = 1.0 + a2 * (-k2 + a2 * (k4 + a2 * (-k6 + a2 * (k8 - a2 * k10))));
    } else if (std::abs(a) <= kSmallAngle) {
      s = a + a * a2 * (-k3 + a2 * (k5 + a2 * (-k7 + a2 * (k9 + a2 * (-k11 + a2 * k13)))));
      c = 1.0 + a2 * (-k2 + a2 * (k4 + a2 * (-k6 + a2 * (k8 + a2 * (-k10 + a2 * (k12 - a2 * k14))))));
    } else {
      s = std::sin(a);
      c = std::cos(a);
    }
  }
  bool empty() const { return steps == 0; }
  void clear() { *this = OdometryBatch{}; }

  /// A heading with its cosine and sine, and those of headings near it by angle addition: the
  /// UKF moves its sigma points, whose headings lie within a few sigma of the mean, with one
  /// libm call for the mean instead of one per point.
  struct Heading {
    double theta, c, s;
    explicit Heading(double t) : theta(t), c(std::cos(t)), s(std::sin(t)) {}
    /// cos and sin of a: angle addition from theta when a is within kSmallAngle of it (exactly
    /// c, s at a = theta), libm otherwise.
    void sinCos(double a, double& sa, double& ca) const {
      const double d = a - theta;
      if (!(std::abs(d) <= kSmallAngle)) {
        sa = std::sin(a);
        ca = std::cos(a);
        return;
      }
      double sd, cd;
      sinCosSmall(d, sd, cd);
      ca = c * cd - s * sd;
      sa = s * cd + c * sd;
    }
  };

  /// pose moved by the composed increment; theta wrapped to (-pi, pi].
  Pose apply(const Pose& pose) const { return apply(pose, Heading(pose.z())); }
  /// The same with the heading's cosine and sine taken near `near` (Heading::sinCos).
  Pose apply(const Pose& pose, const Heading& near) const {
    double s, c;
    near.sinCos(pose.z(), s, c);
    return Pose(pose.x() + c * dx - s * dy, pose.y() + s * dx + c * dy, wrapAngle(pose.z() + dtheta));
  }

  /// Process noise of the whole batch for a batch starting at heading theta0 (world frame).
  Mat3 noise(double theta0) const { return noise(Heading(theta0)); }
  Mat3 noise(const Heading& h0) const {
    const Vec2 d(dx, dy);
    const double s0 = q_sum.z();
    Mat2 m2 = this->m2;  // add() fills the upper triangle
    m2(1, 0) = m2(0, 1);
    const Mat2 A = s0 * d * d.transpose() - d * m1.transpose() - m1 * d.transpose() + m2;  // sum q r r'
    const Vec2 b = s0 * d - m1;                                                           // sum q r
    Mat2 RJ;  // rotation by theta0, then by +90 deg
    const double c = h0.c, s = h0.s;
    RJ << -s, -c, c, -s;
    Mat3 Q = q_sum.asDiagonal();
    Q.topLeftCorner<2, 2>() += RJ * A * RJ.transpose();
    Q.topRightCorner<2, 1>() += RJ * b;
    Q.bottomLeftCorner<1, 2>() += (RJ * b).transpose();
    return Q;
  }
};

}  // namespace lcmloc::core
