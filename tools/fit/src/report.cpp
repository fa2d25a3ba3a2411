#include "lcmloc/fit/report.hpp"

#include <cstdio>

#include "lcmloc/fit/innovation_fit.hpp"

namespace lcmloc::fit {

void printFit(const NoiseFit& f, const LogRead& read) {
  const Recording& r = read.recording;
  std::printf("read: %zu truth, %zu odometry, %zu landmark, %zu beacon, %zu gps messages (%lld refused)%s\n",
              r.truth.size(), r.odometry.size(), r.landmarks.size(), r.beacons.size(), r.gps.size(),
              static_cast<long long>(read.refused), read.damaged ? "; the log is damaged" : "");
  std::printf("%-22s %8s %12s %12s %12s %12s\n", "residual", "n", "median", "mean", "sigma", "rms");
  auto row = [](const char* what, const std::optional<Residuals>& v) {
    if (v)
      std::printf("%-22s %8lld %12.5g %12.5g %12.5g %12.5g\n", what, static_cast<long long>(v->n), v->median, v->mean,
                  v->sigma, v->rms);
  };
  row("landmark range [m]", f.landmark_range);
  row("landmark bearing [rad]", f.landmark_bearing);
  row("beacon range [m]", f.beacon_range);
  for (const auto& [id, v] : f.beacon_range_by_id) {
    const std::string what = "  beacon " + std::to_string(id);
    row(what.c_str(), v);
  }
  row("gps per axis [m]", f.gps);
  if (const auto& c = f.landmark_correlation)
    std::printf("landmark residuals of successive observations: correlation %.2f (range), %.2f (bearing), %lld pairs: "
                "correlation_factor %.3g\n",
                c->range_rho, c->bearing_rho, static_cast<long long>(c->pairs), c->factor);
  if (f.pw_diag)
    std::printf("odometry: %lld windows: pw_diag [%.4g, %.4g, %.4g] per %g m, pw_turn %.4g rad^2/rad\n",
                static_cast<long long>(f.odometry_windows), (*f.pw_diag)[0], (*f.pw_diag)[1], (*f.pw_diag)[2],
                r.pw_distance, *f.pw_turn);
  auto scale = [](const char* what, const std::optional<NoiseFit::Scale>& v) {
    if (v)
      std::printf("%s: truth = %.4g x odometry (+- %.2g, %lld windows)%s\n", what, v->ratio, v->se,
                  static_cast<long long>(v->n), v->significant() ? ": not 1" : "");
  };
  scale("odometry distance scale", f.odometry_scale);
  scale("odometry turn scale", f.yaw_rate_scale);
  if (const auto& lag = f.odometry_lag)
    std::printf("odometry lag: the truth's turn follows the odometry's by %.2f s (RMS of the heading change over 1 s: "
                "%.4g rad at 0 s, %.4g rad at the lag, the truth's own %.4g rad; %lld windows)%s\n",
                lag->seconds, lag->rms_at_zero, lag->rms, lag->truth_rms, static_cast<long long>(lag->n),
                lag->significant() ? ": significant; the scales and the process noise above are fitted to the odometry "
                                     "moved by it (lcmloc-import moves it so in the log it writes)"
                                   : ": not significant");
  for (const auto& n : f.notes) std::printf("note: %s\n", n.c_str());
}

namespace {
RecordingChannels channelsOf(const app::SystemConfig& cfg) {
  return {cfg.channels.odometry, cfg.channels.landmarks, cfg.channels.beacons, cfg.channels.gps};
}
void printNis(const char* title, const std::vector<SensorNis>& nis) {
  if (nis.empty()) {
    std::printf("%s: no sensor decision with a candidate\n", title);
    return;
  }
  std::printf("%s:\n%s", title, nisTable(nis).c_str());
}
}  // namespace

std::string truthFitReport(const LogRead& read, const app::SystemConfig& cfg) {
  const auto f = fitAgainstTruth(read.recording);
  printFit(f, read);
  core::EngineConfig e = app::engineConfig(cfg);
  printNis("NIS with the config as given", nisPerSensor(read.recording, e, channelsOf(cfg)));
  e.filter = withFit(e.filter, f, read.recording.pw_distance);
  printNis("NIS with the fit", nisPerSensor(read.recording, e, channelsOf(cfg)));
  return configFragment(f, read.recording.pw_distance);
}

std::string innovationFitReport(const LogRead& read, const app::SystemConfig& cfg) {
  const Recording& r = read.recording;
  std::printf("read: %zu odometry, %zu landmark, %zu beacon, %zu gps messages (%lld refused)%s; fitted to the "
              "innovations of filter %s\n",
              r.odometry.size(), r.landmarks.size(), r.beacons.size(), r.gps.size(),
              static_cast<long long>(read.refused), read.damaged ? "; the log is damaged" : "",
              cfg.fusion.filter.type.c_str());
  InnovationFitOptions opt;
  opt.channels = channelsOf(cfg);
  const auto f = fitByInnovations(r, app::engineConfig(cfg), opt);
  printNis("NIS with the config as given", f.before);
  if (f.rw_error.first > 0)
    std::printf("gnss.position_rw %.4g m/sqrt(s): mean GPS prediction error %.4g m (%.4g m with the config as given)\n",
                f.filter.gnss.position_rw, f.rw_error.second, f.rw_error.first);
  std::printf("%d run(s) of the filter\n", f.runs);
  printNis("NIS with the fit", f.after);
  for (const auto& n : f.notes) std::printf("note: %s\n", n.c_str());
  return configFragment(f);
}

}  // namespace lcmloc::fit
