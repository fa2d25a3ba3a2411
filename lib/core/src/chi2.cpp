#include "lcmloc/core/chi2.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace lcmloc::core {
namespace {

void checkDof(int dof) {
  if (dof < 1 || dof > 10)
    throw std::invalid_argument("chi2: dof must be in 1..10, got " + std::to_string(dof));
}

}  // namespace

// Regularized lower incomplete gamma P(k/2, x/2) in closed form: start from P(1/2, y) = erf(sqrt y)
// or P(1, y) = 1 - exp(-y) and climb with P(a + 1, y) = P(a, y) - y^a exp(-y) / Gamma(a + 1).
double chi2Cdf(double x, int dof) {
  checkDof(dof);
  if (std::isnan(x)) return x;
  if (x <= 0.0) return 0.0;
  if (std::isinf(x)) return 1.0;
  const double y = 0.5 * x;
  double a = (dof % 2 == 1) ? 0.5 : 1.0;
  double p = (dof % 2 == 1) ? std::erf(std::sqrt(y)) : -std::expm1(-y);
  for (; a < 0.5 * dof; a += 1.0) p -= std::exp(a * std::log(y) - y - std::lgamma(a + 1.0));
  return std::min(1.0, std::max(0.0, p));
}

double chi2Quantile(double p, int dof) {
  checkDof(dof);
  if (!(p > 0.0 && p < 1.0))
    throw std::invalid_argument("chi2: probability must be in (0, 1), got " + std::to_string(p));
  double lo = 0.0, hi = 1.0;
  while (chi2Cdf(hi, dof) < p) hi *= 2.0;  // the CDF is increasing: bracket, then bisect
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi2Cdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace lcmloc::core
