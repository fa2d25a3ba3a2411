// Monte Carlo of the magnetic-ruler scenario (see montecarlo.hpp).
#include "lcmloc/montecarlo/montecarlo.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/core/scoring.hpp"
#include "lcmloc/scenario/scenario_runner.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::montecarlo {
namespace {

using app::ConfigError;

struct FilterStats {
  std::vector<double> rmse, max_error, final_error, nees;
  int lockout_runs = 0, lockout_events = 0, faults_total = 0, faults_rejected = 0,
      valid_rejected = 0, accepted = 0, rejected = 0;
};

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

/// Median, p95, mean and max over the runs (NaN, written as null, when no run was done).
nlohmann::json summary(const std::vector<double>& v) {
  if (v.empty()) return {{"median", NAN}, {"p95", NAN}, {"mean", NAN}, {"max", NAN}};
  const auto s = core::errorStats(v);  // of values >= 0 (errors, NEES): the values themselves
  return {{"median", s.median}, {"p95", s.p95}, {"mean", s.mean}, {"max", s.max}};
}

nlohmann::json report(const Options& o, const sim::ScenarioConfig& sc, const Eigen::Vector3d& pw, int runs_done,
                      uint64_t base, const std::vector<std::string>& names,
                      const std::vector<FilterStats>& stats) {
  nlohmann::json j;
  j["config"] = o.config.empty() ? "(defaults)" : o.config;
  j["scenario"] = sc.name;
  j["runs"] = runs_done;
  j["runs_requested"] = o.runs;
  j["seed_base"] = base;
  j["scale_error"] = sc.odometry.scale_error;
  j["steering_bias_rad"] = sc.odometry.steering_bias;
  j["faults_per_run"] = sc.faults.size();
  j["markers"] = {{"count", sc.markers.count}, {"spacing_m", sc.markers.spacing}};
  j["pw_diag"] = {pw[0], pw[1], pw[2]};
  for (std::size_t i = 0; i < names.size(); ++i) {
    const FilterStats& s = stats[i];
    j["filters"][names[i]] = {
        {"lockout_runs", s.lockout_runs},
        {"lockout_rate", runs_done ? static_cast<double>(s.lockout_runs) / runs_done : 0.0},
        {"lockout_events", s.lockout_events},
        {"rmse_m", summary(s.rmse)},
        {"max_error_m", summary(s.max_error)},
        {"final_error_m", summary(s.final_error)},
        {"mean_nees", summary(s.nees)},
        {"accepted", s.accepted},
        {"rejected", s.rejected},
        {"faults_total", s.faults_total},
        {"faults_rejected", s.faults_rejected},
        {"valid_rejected", s.valid_rejected}};
  }
  return j;
}

}  // namespace

void addOptions(CLI::App& app, Options& o) {
  app.add_option("--runs", o.runs, "number of runs")->capture_default_str()->check(app::positive());
  app.add_option("--seed-base", o.seed_base, "seed of the first run (default: the config's seed)")
      ->check(app::seed());
  app.add_option("--scale-error", o.scale_error, "odometer scale error k [-]")->capture_default_str()->check(CLI::Range(simconfig::kOdometryScaleError.lo, simconfig::kOdometryScaleError.hi));
  app.add_option("--steering-bias-deg", o.steering_bias_deg, "steering-encoder bias [deg]")
      ->capture_default_str()
      ->check(CLI::Range(simconfig::kOdometrySteeringBias.lo * 180.0 / M_PI,
                                simconfig::kOdometrySteeringBias.hi * 180.0 / M_PI));
  app.add_flag("--no-faults", o.no_faults, "run without the configured fault markers");
  app.add_option("--marker-spacing", o.marker_spacing,
                 "markers this many metres apart over the stretch the configured markers cover (default: as configured) [m]")
      ->check(app::positive());
  app.add_option("--pw-diag", o.pw_diag,
                 "process noise Pw of the filters: x [m^2], y [m^2], theta [rad^2] per pw_distance of travel "
                 "(default: the config's fusion.filter.pw_diag)")
      ->expected(3)
      ->delimiter(',')
      ->check(app::nonNegative());
  app.add_option("--filters", o.filters, "comma-separated filter types")->capture_default_str();
  app::addOutputOption(app, o.out, "JSON report file")->capture_default_str();
  app::addOverwriteFlag(app, o.overwrite);
}

int run(const Options& o) {
  app::refuseExistingOutput(o.out, o.overwrite);
  sim::ScenarioConfig sc;
  core::FilterConfig base_filter;
  if (!o.config.empty()) {
    const auto sys = simconfig::loadSimSystemConfig(o.config);
    sc = sys.scenario;
    base_filter = sys.fusion.filter;
  }
  sc.odometry.scale_error = o.scale_error;
  sc.odometry.steering_bias = o.steering_bias_deg * M_PI / 180.0;
  if (o.no_faults) sc.faults.clear();
  if (o.marker_spacing > 0) {
    sc.markers = sim::respaced(sc.markers, o.marker_spacing);
    if (sc.markers.count > simconfig::kMarkerCount.hi)
      throw ConfigError("--marker-spacing", "marker_spacing",
                        fmt::format("{} markers {} m apart: more than markers.count allows ({})", sc.markers.count,
                                    o.marker_spacing, simconfig::kMarkerCount.hi));
  }
  if (!o.pw_diag.empty()) base_filter.pw_diag = Eigen::Vector3d(o.pw_diag[0], o.pw_diag[1], o.pw_diag[2]);

  const auto names = splitList(o.filters);
  if (names.empty()) throw ConfigError("--filters", "filters", "no filter given");
  app::checkFilterList(names, "--filters", "filters");  // the report has one entry per type
  std::vector<core::FilterConfig> filters;
  for (const auto& n : names) {
    auto f = base_filter;
    f.type = n;
    filters.push_back(f);
  }
  const uint64_t base = o.seed_base.value_or(sc.seed);
  spdlog::info("{} runs of '{}' (seeds {}..{}), scale error {}, steering bias {} rad, {} markers {} m apart, "
               "Pw ({}, {}, {}), filters {}",
               o.runs, sc.name, base, base + o.runs - 1, sc.odometry.scale_error, sc.odometry.steering_bias,
               sc.markers.count, sc.markers.spacing, base_filter.pw_diag[0], base_filter.pw_diag[1],
               base_filter.pw_diag[2], o.filters);

  std::vector<FilterStats> stats(names.size());
  int done = 0, next_progress = 1;
  for (int i = 0; i < o.runs && !app::stopRequested(); ++i) {
    sc.seed = base + static_cast<uint64_t>(i);
    const auto res = scenario::runScenario(sc, filters);
    for (std::size_t k = 0; k < names.size(); ++k) {
      const auto& r = res.filters[k];
      FilterStats& s = stats[k];
      s.rmse.push_back(r.rmse_m);
      s.max_error.push_back(r.max_error_m);
      s.final_error.push_back(r.final_error_m);
      s.nees.push_back(r.mean_nees);
      s.lockout_runs += r.locked_out;
      s.lockout_events += r.lockout_events;
      s.faults_total += r.faults_total;
      s.faults_rejected += r.faults_rejected;
      s.valid_rejected += r.valid_rejected;
      s.accepted += r.accepted;
      s.rejected += r.rejected;
      if (r.locked_out) spdlog::info("seed {}: {} locked out", sc.seed, names[k]);
    }
    ++done;
    if (done * 10 >= next_progress * o.runs) {
      spdlog::info("{}% ({} of {} runs)", 100 * done / o.runs, done, o.runs);
      next_progress = done * 10 / o.runs + 1;
    }
  }
  if (done < o.runs) spdlog::warn("stopped after {} of {} runs", done, o.runs);

  const auto j = report(o, sc, base_filter.pw_diag, done, base, names, stats);
  const std::filesystem::path out(o.out);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  std::ofstream f(out);
  if (!(f << j.dump(2) << '\n')) throw std::runtime_error("cannot write " + o.out);
  for (const auto& n : names) {
    const auto& s = j["filters"][n];
    spdlog::info("{}: lock-out {}/{} runs, RMSE median {:.4f} m p95 {:.4f} m, faults rejected "
                 "{}/{}, valid rejected {}", n, s["lockout_runs"].get<int>(), done,
                 s["rmse_m"]["median"].get<double>(), s["rmse_m"]["p95"].get<double>(),
                 s["faults_rejected"].get<int>(), s["faults_total"].get<int>(),
                 s["valid_rejected"].get<int>());
  }
  spdlog::info("report written to {}", o.out);
  return done < o.runs ? app::kExitRuntimeError : app::kExitOk;
}


}  // namespace lcmloc::montecarlo
