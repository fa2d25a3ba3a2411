#pragma once
namespace lcmloc::core {

/// Quantile of the chi-square distribution with dof degrees of freedom (1..10) at probability p
/// in (0, 1); e.g. chi2Quantile(0.99, 1) = 6.635, chi2Quantile(0.99, 2) = 9.210.
double chi2Quantile(double p, int dof);

/// CDF of the chi-square distribution with dof degrees of freedom at x >= 0.
double chi2Cdf(double x, int dof);

/// Quantile of the chi-square distribution with any dof > 0 degrees of freedom (not only an
/// integer, and as large as the summed dof of a long series) at probability p in (0, 1).
/// Throws std::invalid_argument outside those ranges.
double chi2QuantileAnyDof(double p, double dof);

}  // namespace lcmloc::core
