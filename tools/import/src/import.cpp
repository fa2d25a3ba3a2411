// lcmloc-import (import.hpp): the directory's files read (read_files.cpp) and converted
// (convert_rows.cpp), then run.lcmlog, map.csv and a config.yaml for lcmloc-replay written;
// the time-unit and time-base rules and the report.
#include "lcmloc/import/import.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "import_files.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/fit/fit_log.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/import/checks.hpp"
#include "lcmloc/odometry_t.hpp"

namespace lcmloc::import {
namespace fs = std::filesystem;
namespace {

/// The options that go into config.yaml, refused with the flag's name when config.yaml would
/// not accept them (the replay would refuse the generated file).
void checkOptions(const ImportOptions& opt) {
  if (opt.wheelbase != 0.0) checkFilterValue("--wheelbase", "wheelbase", fmt::format("{}", opt.wheelbase));
  if (opt.initial_pose)
    checkFilterValue("--initial-pose", "initial_pose",
                     fmt::format("[{}, {}, {}]", (*opt.initial_pose)[0], (*opt.initial_pose)[1], (*opt.initial_pose)[2]));
  if (!opt.filter.empty()) checkFilterValue("--filter", "type", opt.filter);
}

/// A number as config.yaml gets it: the shortest text that reads back to the same double, so
/// that a value inside a bound the config checks stays inside it (3.141593 for pi did not).
std::string num(double v) { return fmt::format("{}", v); }

/// The fitted values that d takes (a sigma of 0, from data quantized coarser than its noise, is
/// not taken), and the comment lines that say so.
std::string applyFit(const fit::NoiseFit* f, core::FilterConfig& d) {
  if (!f) return "";
  std::string said = "    # Noise fitted against the ground truth (lcmloc-fit-noise; docs/import_formats.md):";
  auto take = [&said](const char* key, double v, double& into) {
    if (!(v > 0)) return;
    into = v;
    said += std::string(" ") + key;
  };
  if (f->pw_diag) {
    d.pw_diag = *f->pw_diag;
    d.pw_turn = *f->pw_turn;
    said += " pw_diag pw_turn";
  }
  if (f->landmark_range) take("range_std", f->landmark_range->sigma, d.landmarks.range_std);
  if (f->landmark_bearing) take("bearing_std", f->landmark_bearing->sigma, d.landmarks.bearing_std);
  if (f->landmark_correlation) take("correlation_factor", f->landmark_correlation->factor, d.landmarks.correlation_factor);
  if (f->beacon_range) take("beacon_std", f->beacon_range->sigma, d.landmarks.beacon_std);
  if (f->gps) take("gps_std", f->gps->sigma, d.gnss.gps_std);
  return said + "\n";
}

/// The text of config.yaml for lcmloc-replay: the filter `filter` from the initial pose of
/// --initial-pose, else the first ground-truth pose, else 0; map.csv when there is a map.
std::string configText(const ImportOptions& opt, const std::string& filter, std::size_t map_size,
                       const detail::Converted& conv, const fit::NoiseFit* fitted = nullptr) {
  const auto& first_truth = conv.first_truth;
  core::Vec3 pose = opt.initial_pose ? *opt.initial_pose : first_truth ? *first_truth : core::Vec3::Zero();
  pose[2] = core::wrapAngle(pose[2]);  // (-pi, pi]
  std::string source = " (no ground truth)";
  if (opt.initial_pose) source = "";
  else if (conv.truth_heading == "row") source = " (first ground-truth row)";
  else if (conv.truth_heading == "travel")
    source = " (first ground-truth position; heading: its direction of travel, the truth has none)";
  else if (first_truth) source = " (first ground-truth position; the truth has no heading and does not move: 0)";
  core::FilterConfig d;
  const std::string noise = applyFit(fitted, d);
  std::ostringstream c;
  c << "# Written by lcmloc-import from " << opt.dir << " (docs/import_formats.md).\n"
    << "# Replay: lcmloc-replay run.lcmlog --config config.yaml --with-inputs -o estimates.lcmlog\n"
    << "scenario: {name: import, seed: 1, realtime_factor: 0.0}\n"
    << "markers: {count: 0}            # the map is fusion.map_file\n"
    << fmt::format("datum: {{latitude: {}, longitude: {}, altitude: {}}}\n", num(opt.datum.latitude),
                   num(opt.datum.longitude), num(opt.datum.altitude))
    << "fusion:\n"
    << "  shadow: []\n";
  if (map_size > 0) c << "  map_file: map.csv              # id,x,y [m]\n";
  c << "  filter:\n"
    << "    type: " << filter << "\n"
    << fmt::format("    initial_pose: [{}, {}, {}]   # x [m], y [m], theta [rad]{}\n", num(pose[0]), num(pose[1]),
                   num(pose[2]), source)
    << fmt::format("    p0_diag: [{}, {}, {}]        # initial variances [m^2, m^2, rad^2]\n", num(d.p0_diag[0]),
                   num(d.p0_diag[1]), num(d.p0_diag[2]));
  if (opt.wheelbase > 0) c << fmt::format("    wheelbase: {}\n", num(opt.wheelbase));
  c << noise;
  c << fmt::format("    pw_diag: [{}, {}, {}]     # process noise accumulated over pw_distance of travel\n",
                   num(d.pw_diag[0]), num(d.pw_diag[1]), num(d.pw_diag[2]))
    << fmt::format("    pw_distance: {}                # [m]\n", num(d.pw_distance))
    << fmt::format("    pw_turn: {}                   # heading variance per radian turned [rad^2/rad]\n", num(d.pw_turn))
    << fmt::format("    landmarks: {{range_std: {}, bearing_std: {}, beacon_std: {}, correlation_factor: {}}}  # [m], [rad], [m], [-]\n",
                   num(d.landmarks.range_std), num(d.landmarks.bearing_std), num(d.landmarks.beacon_std),
                   num(d.landmarks.correlation_factor));
  std::vector<std::string> gnss;
  if (fitted && fitted->gps && fitted->gps->sigma > 0) gnss.push_back("gps_std: " + num(d.gnss.gps_std));
  if (conv.imu_without_mag) gnss.push_back("use_magnetometer: false");  // the IMU rows have no magnetometer
  if (!gnss.empty()) c << "    gnss: {" << fmt::format("{}", fmt::join(gnss, ", ")) << "}\n";
  c << "    gate: {enabled: true, probability: 0.99}\n";
  // The odometry's scales against the truth, where they differ from 1 beyond their uncertainty:
  // the filter's self-calibration states start there (ukf_landmarks; docs/configuration.md).
  std::vector<std::string> cal;
  auto scale = [&cal](const std::optional<fit::NoiseFit::Scale>& v, const char* key) {
    if (!v || !v->significant()) return;
    cal.push_back(fmt::format("{}: true, {}_mean: {}, {}_std: {}", key, key, num(v->ratio - 1.0), key,
                              num(std::max(3.0 * v->se, 0.05))));
  };
  if (fitted && filter == "ukf_landmarks") {
    scale(fitted->odometry_scale, "odo_scale");
    scale(fitted->yaw_rate_scale, "yaw_rate_scale");
    // The beacons' range bias, where one differs from 0 beyond its uncertainty: a state per
    // beacon when the map allows it, one shared otherwise.
    if (const auto& b = fitted->beacon_bias)
      cal.push_back(fmt::format("beacon_bias: {}, beacon_bias_mean: {}, beacon_bias_std: {}",
                                map_size <= static_cast<std::size_t>(core::FilterConfig::Calibration::kMaxPerBeacon) ? "per_beacon" : "shared", num(b->mean),
                                num(b->std)));
  }
  if (!cal.empty())
    c << "    calibration: {" << fmt::format("{}", fmt::join(cal, ", "))
      << "}   # fitted against the truth: the odometry's scales, the beacons' range bias\n";
  return c.str();
}

/// Every value of the config text read back by the loader lcmloc-replay uses: a value it would
/// refuse is an error before anything is written.
void checkConfigText(const std::string& text, const std::string& path) {
  try {
    app::parseSystemConfig(text, path);
  } catch (const app::ConfigError& e) {
    throw std::runtime_error(std::string("the config.yaml made for this import is one lcmloc-replay would refuse, so "
                                         "nothing is written (give the value with an option): ") + e.what());
  }
}

/// The config with the noise fitted against the truth of the log just written (read back as the
/// replay reads it); the fit's lines into r.noise_fit. A fitted config the loader would refuse
/// is not used (the defaults stay, and a line says why).
std::string fittedConfig(const ImportOptions& opt, ImportResult& r, std::size_t map_size, detail::Converted& conv,
                         const std::string& plain) {
  const fit::LogRead read = fit::readRecording(r.log_path, app::parseSystemConfig(plain, r.config_path));
  const fit::NoiseFit f = fit::fitAgainstTruth(read.recording);
  const std::string text = configText(opt, r.filter, map_size, conv, &f);
  try {
    app::parseSystemConfig(text, r.config_path);
  } catch (const app::ConfigError& e) {
    r.noise_fit.push_back(std::string("noise fit not used (the filter's defaults kept): ") + e.what());
    return plain;
  }
  auto line = [&r](const char* what, const std::optional<fit::Residuals>& v) {
    if (v) r.noise_fit.push_back(fmt::format("noise fit: {} sigma {:.4g} (median {:.4g}, {} residuals)", what, v->sigma, v->median, v->n));
  };
  line("landmark range [m]", f.landmark_range);
  line("landmark bearing [rad]", f.landmark_bearing);
  line("beacon range [m]", f.beacon_range);
  line("gps per axis [m]", f.gps);
  if (const auto& c = f.landmark_correlation)
    r.noise_fit.push_back(fmt::format("noise fit: landmark residuals of successive observations correlate {:.2f} (range), "
                                      "{:.2f} (bearing), {} pairs: each update weighs an observation as {:.3g} times its variance",
                                      c->range_rho, c->bearing_rho, c->pairs, c->factor));
  if (f.pw_diag)
    r.noise_fit.push_back(fmt::format("noise fit: odometry pw_diag [{:.4g}, {:.4g}, {:.4g}] per {} m, pw_turn {:.4g} ({} windows)",
                                      (*f.pw_diag)[0], (*f.pw_diag)[1], (*f.pw_diag)[2], read.recording.pw_distance,
                                      *f.pw_turn, f.odometry_windows));
  auto scale = [&r](const char* what, const std::optional<fit::NoiseFit::Scale>& v) {
    if (v)
      r.noise_fit.push_back(fmt::format("noise fit: odometry {} scale: truth = {:.4g} x odometry (+- {:.2g}, {} windows){}",
                                        what, v->ratio, v->se, v->n,
                                        v->significant() ? ": the filter's calibration state starts there" : ""));
  };
  scale("distance", f.odometry_scale);
  scale("turn", f.yaw_rate_scale);
  if (f.beacon_bias && r.filter == "ukf_landmarks")
    r.noise_fit.push_back(fmt::format("noise fit: beacon range bias: {} of {} beacons' median residual differs from 0 "
                                      "(their median {:.3g} m, spread {:.2g} m): the filter's range-bias states start there",
                                      f.beacon_bias->beacons, f.beacon_bias->of, f.beacon_bias->mean, f.beacon_bias->std));
  if (const auto& lag = f.odometry_lag) {
    if (lag->significant()) {
      // The odometry written at the time of its motion (the scales and the process noise were
      // fitted to it so).
      conv.log.retime<lcmloc::odometry_t>(opt.channels.odometry, std::llround(lag->seconds * 1e6));
      conv.log.write(r.log_path);
      r.first_utime = conv.log.firstUtime();
      r.last_utime = conv.log.lastUtime();
    }
    r.noise_fit.push_back(fmt::format(
        "noise fit: odometry lag: the truth's turn follows the odometry's by {:.2f} s (RMS of the heading change over "
        "1 s: {:.4g} rad at 0 s, {:.4g} rad at the lag, the truth's own {:.4g} rad; {} windows){}",
        lag->seconds, lag->rms_at_zero, lag->rms, lag->truth_rms, lag->n,
        lag->significant() ? ": the odometry's times are moved by it in the log" : ": not significant, not applied"));
  }
  for (const auto& n : f.notes) r.noise_fit.push_back("noise fit: " + n);
  return text;
}

}  // namespace

std::string toString(TimeUnit u) {
  switch (u) {
    case TimeUnit::Seconds: return "seconds";
    case TimeUnit::Microseconds: return "microseconds";
    default: return "auto";
  }
}
std::string toString(TimeBase b) {
  switch (b) {
    case TimeBase::Absolute: return "absolute";
    case TimeBase::Relative: return "relative";
    default: return "auto";
  }
}

TimeUnit detectTimeUnit(const std::vector<double>& t) {
  if (t.empty()) return TimeUnit::Seconds;
  std::vector<double> mag;  // the median, not the largest: one wrong time does not decide
  for (double v : t) mag.push_back(std::abs(v));
  std::nth_element(mag.begin(), mag.begin() + mag.size() / 2, mag.end());
  if (mag[mag.size() / 2] >= 1e11) return TimeUnit::Microseconds;
  std::vector<double> steps;
  for (std::size_t i = 1; i < t.size(); ++i)
    if (t[i] > t[i - 1]) steps.push_back(t[i] - t[i - 1]);
  if (steps.empty()) return TimeUnit::Seconds;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2] >= 1000.0 ? TimeUnit::Microseconds : TimeUnit::Seconds;
}

TimeBase detectTimeBase(int64_t first_utime) {
  return first_utime >= 1'000'000'000'000'000LL ? TimeBase::Absolute : TimeBase::Relative;
}

ImportResult importDirectory(const ImportOptions& opt) {
  ImportResult r;
  std::error_code ec;
  if (!fs::is_directory(opt.dir, ec)) throw std::runtime_error("'" + opt.dir + "' is not a directory");
  std::vector<fs::path> paths;
  for (const auto& e : fs::directory_iterator(opt.dir, ec))  // (a directory named *.csv: skipped, saying so)
    if (e.path().extension() == ".csv") paths.push_back(e.path());
  if (ec) throw std::runtime_error("cannot list '" + opt.dir + "': " + ec.message());
  std::sort(paths.begin(), paths.end());
  checkOptions(opt);
  if (!opt.out_dir.empty()) {
    const std::vector<std::string> inputs(paths.begin(), paths.end());
    for (const char* name : {"run.lcmlog", "map.csv", "config.yaml"})
      app::refuseOutputOverInputs("--output", (fs::path(opt.out_dir) / name).string(), inputs);
  }

  // Pass 1: recognise the files, read the map, split rows and read the time column.
  core::MarkerMap map;
  std::vector<detail::DataFile> files = detail::readDataFiles(paths, opt, r, map);
  r.map_size = static_cast<int64_t>(map.size());
  // All files must share one clock; odometry and ground truth come as one stream each.
  const std::vector<const detail::DataFile*> in_time = detail::inTimeOrder(files);
  // Pass 2: convert.
  detail::Converted conv = detail::convertRows(files, in_time, map, opt, r);
  EventLog& log = conv.log;

  log.sort();
  r.messages = static_cast<int64_t>(log.size());
  r.first_utime = log.firstUtime();
  r.last_utime = log.lastUtime();
  r.files.clear();
  for (const auto& f : files) r.files.push_back(f.report);
  if (conv.landmarks_written > 0 && conv.landmarks_without_identity == conv.landmarks_written && !conv.have_beacons &&
      !conv.have_gps)
    r.warnings.push_back(fmt::format(
        "warning: every one of the {} landmark observations is without identity (landmark_id -1) and nothing else "
        "measures the position: the filter can only associate them with the map from its predicted pose, never "
        "confirm that pose, and observations of things not in the map (other robots) are taken for landmarks when "
        "one is near; the run is dead reckoning at best",
        conv.landmarks_written));
  if (!opt.filter.empty()) r.filter = opt.filter;
  else if (conv.have_landmarks || conv.have_beacons) r.filter = "ukf_landmarks";
  else if (conv.have_gps) r.filter = "ukf_gps";
  else r.filter = "dead_reckoning";

  if (!opt.out_dir.empty() && r.usable()) {
    r.config_path = (fs::path(opt.out_dir) / "config.yaml").string();
    const std::string config = configText(opt, r.filter, map.size(), conv);
    checkConfigText(config, r.config_path);
    fs::create_directories(opt.out_dir, ec);
    if (ec) throw std::runtime_error("cannot create '" + opt.out_dir + "': " + ec.message());
    r.log_path = (fs::path(opt.out_dir) / "run.lcmlog").string();
    log.write(r.log_path);
    if (!map.empty()) {
      r.map_path = (fs::path(opt.out_dir) / "map.csv").string();
      app::csv::writeMap(r.map_path, map);
    }
    std::string text = config;
    if (opt.fit_noise && conv.first_truth) text = fittedConfig(opt, r, map.size(), conv, config);
    std::ofstream out(r.config_path);
    out << text;
    if (!out.flush()) throw std::runtime_error("cannot write '" + r.config_path + "'");
  }
  return r;
}

std::string importSummary(const ImportResult& r, int max_refusals) {
  std::string s;
  for (const auto& f : r.files)
    s += fmt::format("{}: {} ({}), times in {} ({}): {} rows read, {} refused, {} messages, {:.3f} s .. {:.3f} s\n",
                     f.path, f.kind, f.header, toString(f.unit), toString(f.base), f.rows, f.refused, f.written,
                     f.first_utime * 1e-6, f.last_utime * 1e-6);
  for (const auto& k : r.skipped) s += "skipped " + k + "\n";
  if (r.map_size > 0) s += fmt::format("map: {} entries\n", r.map_size);
  s += fmt::format("total: {} messages, time span {:.3f} s .. {:.3f} s ({:.3f} s), {} rows refused\n", r.messages,
                   r.first_utime * 1e-6, r.last_utime * 1e-6, (r.last_utime - r.first_utime) * 1e-6,
                   r.refusals.size());
  const std::size_t shown = std::min(r.refusals.size(), static_cast<std::size_t>(std::max(max_refusals, 0)));
  for (std::size_t i = 0; i < shown; ++i)
    s += fmt::format("refused {}:{}: {}\n", r.refusals[i].file, r.refusals[i].line, r.refusals[i].reason);
  if (shown < r.refusals.size()) s += fmt::format("... and {} more refused rows\n", r.refusals.size() - shown);
  for (const auto& n : r.noise_fit) s += n + "\n";
  for (const auto& w : r.warnings) s += w + "\n";
  if (!r.log_path.empty())
    s += fmt::format("wrote {}{}, {} (filter {})\n", r.log_path, r.map_path.empty() ? "" : ", " + r.map_path,
                     r.config_path, r.filter);
  return s;
}

}  // namespace lcmloc::import
