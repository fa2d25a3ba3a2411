#pragma once
// Scoring of estimates against a reference, written once for every tool that scores: the
// evaluation (lcmloc-evaluate), the scenario runner, the Monte Carlo and the experiments.
// Error statistics (RMSE, mean, percentiles, max), NEES, the chi-square consistency test of
// NEES / NIS samples, drift over travelled distance and gate statistics per filter and sensor.
// Eigen and the standard library only. Definitions: docs/evaluate.md.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace lcmloc::core {

// --- errors -----------------------------------------------------------------------------------

/// Sorted-sample percentile, linear between order statistics (numpy's default); q in [0, 1].
/// 0 for no sample.
double percentile(std::vector<double> v, double q);

/// Nearest-rank percentile: the smallest sample with at least a fraction q of the samples at or
/// below it (the k-th smallest, k = ceil(q n)); 0 for no sample.
double percentileNearestRank(std::vector<double> v, double q);

struct ErrorStats {
  int64_t n = 0;
  double rmse = 0, mean = 0, median = 0, p95 = 0, max = 0;
};

/// Statistics of the absolute values (an error's sign does not count); all 0 for no sample.
ErrorStats errorStats(const std::vector<double>& v);

/// Root mean square of the values (0 for none): sqrt(sum v^2 / n).
double rms(const std::vector<double>& v);

// --- consistency ------------------------------------------------------------------------------

/// Normalized estimation error squared e' P^-1 e; nullopt when P is not positive definite.
template <int N>
std::optional<double> nees(const Eigen::Matrix<double, N, 1>& e, const Eigen::Matrix<double, N, N>& P) {
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(P);
  if (llt.info() != Eigen::Success) return std::nullopt;
  return e.dot(llt.solve(e));
}

struct ConsistencyStats {
  int dof = 0;
  int64_t samples = 0;
  double mean = 0;
  double mean_lo = 0, mean_hi = 0;       ///< two-sided bounds of the mean over `samples` draws
  double sample_lo = 0, sample_hi = 0;   ///< two-sided per-sample interval
  double fraction_inside = 0;            ///< of samples inside [sample_lo, sample_hi]
  std::string verdict = "none";          ///< honest, optimistic, conservative, none (no samples)
  /// Samples of a time series are correlated; the same test with the effective sample size
  /// n_eff = n / (1 + 2 sum of the autocorrelations) (Geyer's initial positive sequence).
  double effective_samples = 0;
  double mean_lo_effective = 0, mean_hi_effective = 0;
  std::string verdict_effective = "none";
};

/// Effective sample size of a series (n when uncorrelated, less when positively correlated).
double effectiveSampleSize(const std::vector<double>& series);

/// Mean of values (each chi-square with its dof when consistent) against the bounds; values
/// and dofs have equal length. sample bounds use dofs.front() (all equal in practice).
ConsistencyStats consistency(const std::vector<double>& values, const std::vector<int>& dofs,
                             double confidence);

// --- drift ------------------------------------------------------------------------------------

struct DriftStats {
  double length_m = 0;
  int64_t segments = 0;                  ///< one per start with a segment of that length
  double mean_pct = 0, median_pct = 0, max_pct = 0;
};

/// One scored estimate as drift sees it: the distance travelled along the reference up to it
/// and its position error.
struct DriftSample {
  double distance = 0, err_x = 0, err_y = 0;
};

/// Drift over segments of `length` metres of travel: from each sample to the first one at least
/// `length` further along, the change of the position error over the distance travelled [%].
DriftStats drift(const std::vector<DriftSample>& samples, double length);

// --- gate statistics --------------------------------------------------------------------------

/// One gate decision as scored (a gate_decision_t, a core::GateDecision).
struct GateRecord {
  int64_t utime = 0;
  std::string filter, sensor, reason;
  int dim = 0;                           ///< innovation dimension (the NIS's degrees of freedom)
  double nis = 0;                        ///< v' S^-1 v
  bool accepted = false;
  int64_t measurement_seq = -1;          ///< seq of the measurement on its sensor channel
  double gate = 0;                       ///< the threshold nis was compared with (inf: no gate)
};

struct GateGroup {
  std::string filter, sensor;            ///< "*" when aggregated over all
  int64_t decisions = 0, accepted = 0, rejected = 0, ignored = 0;
  std::map<std::string, int64_t> reasons;
  double mean_dof = 0;                   ///< mean innovation dimension of the accepted ones
  ConsistencyStats nis;                  ///< NIS of the accepted measurements
  double nis_mean_all = 0;               ///< mean NIS over every decision with a finite NIS
  /// The longest run of rejections in a row (ignored decisions neither break nor count) of a
  /// group of one filter (filter "*": 0): its decisions, and how long the filter went without
  /// an accepted one: from the first rejection to the acceptance that ended the run (to the last
  /// rejection when none did) [s].
  int64_t longest_rejection_run = 0;
  double longest_rejection_s = 0;
};

struct GateStats {
  std::vector<GateGroup> by_filter_sensor, by_filter, by_sensor;  ///< sorted by name
};

/// A decision whose reason is "dead_reckoning" is ignored: the filter uses no measurement.
bool isIgnoredDecision(const std::string& reason);

/// Counts per (filter, sensor), per filter, per sensor. An ignored decision (isIgnoredDecision)
/// is counted as such, the others are accepted or rejected.
GateStats gateStatistics(const std::vector<GateRecord>& gates, double confidence);

/// Decisions on measurements some of which are known faults (announced on FAULT_EVENTS, or
/// injected by a simulated fault injector).
struct FaultCounts {
  int accepted = 0, rejected = 0, ignored = 0;
  int faults_decided = 0;                ///< decisions on a fault (ignored ones included)
  int faults_accepted = 0, faults_rejected = 0;
  int valid_rejected = 0;                ///< genuine measurements rejected
};

/// Adds one decision to the counts.
void countDecision(FaultCounts& c, bool accepted, const std::string& reason, bool is_fault);

}  // namespace lcmloc::core
