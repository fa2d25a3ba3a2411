#pragma once
// lcmloc-ctl status: the fusion daemon's latest FUSION_STATUS and its wall-clock timing
// (FUSION_TIMING, fusion_timing_t), printed as text.
#include <iosfwd>
#include <optional>
#include <string>

#include "lcmloc/app/config.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/fusion_timing_t.hpp"

namespace lcmloc::ctl {

/// The timing as a table: per channel delay p50 / max [ms], age [s], rate [Hz]; per step
/// processing time p50 / p99 / max [ms].
void printTiming(std::ostream& out, const lcmloc::fusion_timing_t& t);

/// Waits up to timeout [s, wall] for a FUSION_TIMING and a FUSION_STATUS, prints what came.
/// Returns app::kExitOk, or kExitNoAnswer when no timing came. (lcmloc-ctl status prints the
/// process table first, then this.)
int fusionStatus(const app::SystemConfig& cfg, const std::string& lcm_url, double timeout);

}  // namespace lcmloc::ctl
