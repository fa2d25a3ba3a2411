#pragma once
// Models of the GPS + IMU + encoder + steering method (Choi and Kong, seeds/002), written once
// and used by the time-varying EKF (tvekf), the UKF over the same sensors (ukf_gps), the IMU
// sensor model and the tests. Frames: world X east, Y north, heading theta from X, CCW;
// body x forward, y left, z up. Derivations: docs/tvekf.md.
#include "lcmloc/core/types.hpp"

namespace lcmloc::core::gnss {

/// §2.1, eq. 2-3: travelled distance s and speed v driven by the forward acceleration a, held
/// constant over a sample period T (zero-order hold):
///   x(k+1) = A x(k) + B a(k),  x = [s, v]',  s(k) = C x(k),
///   A = [1 T; 0 1],  B = [T^2/2; T],  C = [1 0].
/// The paper prints A = [1 1; 0 1] and B = [T; 1]: garbled (A lacks the period T, and B is
/// neither the exact [T^2/2; T] nor dimensionally consistent). These are derived from
/// s'' = a by integrating twice over one period.
Mat2 kinematicA(double T);
Vec2 kinematicB(double T);
/// x(k+1) = A x(k) + B a.
Vec2 kinematicStep(const Vec2& sv, double a, double T);

/// §2.2, eq. 10: heading rate of a car-like vehicle at speed v [m/s] and steering psi [rad]
/// with wheelbase L [m]: v tan(psi) / L. The heading advances by T times this.
double headingRate(double v, double psi, double wheelbase);

/// §2.3, eq. 17 (small change of heading over T): p(k+1) = p(k) + v T [cos theta, sin theta]'.
/// (The paper's heading is measured from north, hence its [sin, cos]; here theta is from east.)
Vec2 positionStep(const Vec2& p, double v, double theta, double T);

/// Heading of a level vehicle from a body-frame magnetometer reading [gauss]: the horizontal
/// field points to magnetic north, which lies `declination` (east positive) east of true
/// north (world +Y), i.e. at world angle pi/2 - D; in the body it appears at
/// atan2(m_y, m_x) = pi/2 - D - theta. Returns theta in (-pi, pi]; NaN when the horizontal
/// field is zero.
double magnetometerHeading(const Vec3& mag, double declination);

/// Inverse of magnetometerHeading (the sensor model): the Earth field in the body frame of a
/// level vehicle at heading theta, horizontal intensity h [gauss] and vertical component
/// z [gauss] (up positive; negative in the northern hemisphere).
Vec3 earthFieldBody(double theta, double declination, double horizontal, double vertical);

}  // namespace lcmloc::core::gnss
