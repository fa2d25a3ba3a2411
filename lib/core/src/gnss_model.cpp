#include "lcmloc/core/gnss_model.hpp"

#include <cmath>
#include <limits>

#include "lcmloc/core/angles.hpp"

namespace lcmloc::core::gnss {

Mat2 kinematicA(double T) {
  Mat2 A;
  A << 1.0, T, 0.0, 1.0;
  return A;
}

Vec2 kinematicB(double T) { return Vec2(0.5 * T * T, T); }

Vec2 kinematicStep(const Vec2& sv, double a, double T) {
  return Vec2(sv[0] + T * sv[1] + 0.5 * T * T * a, sv[1] + T * a);
}

double headingRate(double v, double psi, double wheelbase) { return v * std::tan(psi) / wheelbase; }

Vec2 positionStep(const Vec2& p, double v, double theta, double T) {
  return Vec2(p[0] + v * T * std::cos(theta), p[1] + v * T * std::sin(theta));
}

double magnetometerHeading(const Vec3& mag, double declination) {
  if (!(mag[0] != 0.0 || mag[1] != 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return wrapAngle(M_PI / 2 - declination - std::atan2(mag[1], mag[0]));
}

Vec3 earthFieldBody(double theta, double declination, double horizontal, double vertical) {
  const double a = M_PI / 2 - declination - theta;  // angle of magnetic north in the body
  return Vec3(horizontal * std::cos(a), horizontal * std::sin(a), vertical);
}

}  // namespace lcmloc::core::gnss
