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

namespace lcmloc::core {
namespace {

/// Regularized incomplete gamma functions P(a, x) and Q(a, x) = 1 - P(a, x), each computed
/// where it is accurate: the series of P below a + 1, the continued fraction of Q above
/// (Numerical Recipes' gser / gcf, modified Lentz).
struct GammaPQ {
  double p = 0, q = 1;
};

GammaPQ incompleteGamma(double a, double x) {
  if (x <= 0) return {0.0, 1.0};
  const double log_prefix = a * std::log(x) - x - std::lgamma(a);
  constexpr double kEps = 1e-16;
  constexpr int kMaxIter = 1'000'000;  // the series needs about sqrt(a) terms per digit
  if (x < a + 1.0) {
    double ap = a, del = 1.0 / a, sum = del;
    for (int i = 0; i < kMaxIter; ++i) {
      ap += 1.0;
      del *= x / ap;
      sum += del;
      if (std::abs(del) < std::abs(sum) * kEps) break;
    }
    const double p = std::min(1.0, sum * std::exp(log_prefix));
    return {p, 1.0 - p};
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < kMaxIter; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double del = d * c;
    h *= del;
    if (std::abs(del - 1.0) < kEps) break;
  }
  const double q = std::min(1.0, std::exp(log_prefix) * h);
  return {1.0 - q, q};
}

}  // namespace

double chi2QuantileAnyDof(double p, double dof) {
  if (!(dof > 0) || std::isinf(dof)) throw std::invalid_argument("chi2: dof must be positive");
  if (!(p > 0 && p < 1)) throw std::invalid_argument("chi2: probability must be in (0, 1)");
  const double a = 0.5 * dof;
  // f(x) = P(a, x) - p, compared through the smaller tail so that p near 1 keeps its digits.
  const bool upper = p > 0.5;
  const double target = upper ? 1.0 - p : p;
  auto f = [&](double x) {
    const GammaPQ g = incompleteGamma(a, x);
    return upper ? target - g.q : g.p - target;  // increasing in x either way
  };
  // Wilson-Hilferty start, then Newton steps kept inside a bracket (bisection when they leave it).
  double lo = 0.0, hi = std::max(1.0, a);
  while (f(hi) < 0) {
    lo = hi;
    hi *= 2.0;
  }
  double zl = -40.0, zh = 40.0;  // the standard normal quantile of p, by bisection
  for (int i = 0; i < 200 && zh - zl > 1e-12; ++i) {
    const double zm = 0.5 * (zl + zh);
    (0.5 * std::erfc(-zm / std::sqrt(2.0)) < p ? zl : zh) = zm;
  }
  const double z = 0.5 * (zl + zh);
  const double c = 2.0 / (9.0 * dof);
  double x = 0.5 * dof * std::pow(std::max(0.0, 1.0 - c + z * std::sqrt(c)), 3.0);  // gamma scale: chi2 / 2
  if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
  for (int i = 0; i < 500; ++i) {
    const double fx = f(x);
    if (fx == 0) break;
    (fx < 0 ? lo : hi) = x;
    // d/dx P(a, x) = x^(a-1) e^-x / Gamma(a)
    const double density = std::exp((a - 1.0) * std::log(x) - x - std::lgamma(a));
    double next = x - fx / density;
    if (!(next > lo && next < hi) || !std::isfinite(next)) next = 0.5 * (lo + hi);
    if (std::abs(next - x) <= 1e-15 * x || hi - lo <= 1e-15 * hi) {
      x = next;
      break;
    }
    x = next;
  }
  return 2.0 * x;
}

}  // namespace lcmloc::core
