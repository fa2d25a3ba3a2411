#pragma once
// lcmloc-fit-noise's table of residuals on stdout.
#include "lcmloc/fit/fit_log.hpp"

namespace lcmloc::fit {

void printFit(const NoiseFit& f, const LogRead& read);

}  // namespace lcmloc::fit
