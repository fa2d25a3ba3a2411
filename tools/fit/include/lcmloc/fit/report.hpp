#pragma once
// lcmloc-fit-noise's report on stdout: the residuals or the innovations' scaling, and each
// sensor's NIS against its chi-square band.
#include <string>

#include "lcmloc/app/config.hpp"
#include "lcmloc/fit/fit_log.hpp"

namespace lcmloc::fit {

void printFit(const NoiseFit& f, const LogRead& read);

/// Fits against the truth, prints the residuals and the NIS of the filter with the fit (and
/// without), returns the config fragment.
std::string truthFitReport(const LogRead& read, const app::SystemConfig& cfg);

/// Fits to the innovations (no truth needed), prints the NIS before and after, returns the
/// config fragment.
std::string innovationFitReport(const LogRead& read, const app::SystemConfig& cfg);

}  // namespace lcmloc::fit
