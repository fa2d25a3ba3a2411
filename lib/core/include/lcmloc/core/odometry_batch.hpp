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
  bool empty() const { return steps == 0; }
  void clear() { *this = OdometryBatch{}; }

  /// pose moved by the composed increment; theta wrapped to (-pi, pi].
  Pose apply(const Pose& pose) const { return apply(pose, SinCosNear(pose.z())); }
  /// The same with the heading's cosine and sine taken near `near` (SinCosNear::sinCos: the
  /// UKF's sigma points, around the mean).
  Pose apply(const Pose& pose, const SinCosNear& near) const {
    double s, c;
    near.sinCos(pose.z(), s, c);
    return Pose(pose.x() + c * dx - s * dy, pose.y() + s * dx + c * dy, wrapAngle(pose.z() + dtheta));
  }

  /// Process noise of the whole batch for a batch starting at heading h0.theta (world frame).
  Mat3 noise(const SinCosNear& h0) const {
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
