#include "lcmloc/landmark_experiment/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/landmark_fix.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/sim/scenario_config.hpp"
#include "lcmloc/core/scoring.hpp"
#include "lcmloc/eval/report.hpp"

namespace lcmloc::landmark_experiment {

namespace fix = core::landmark;
using Vec2 = Eigen::Vector2d;

namespace {

constexpr double kAs = 1.0 / sim::kArcSec;  // rad -> arc seconds

/// Centroid of the triangle of the three lines through lms[i] with azimuths az[i] (clockwise
/// from north); false when two lines are parallel.
bool triangleCentroid(const std::vector<Vec2>& lms, const double* az, Vec2* c) {
  Vec2 sum = Vec2::Zero();
  for (int k = 0; k < 3; ++k) {
    const int i = k, j = (k + 1) % 3;
    const Vec2 di(std::sin(az[i]), std::cos(az[i])), dj(std::sin(az[j]), std::cos(az[j]));
    const double den = di.x() * dj.y() - di.y() * dj.x();
    if (std::abs(den) < 1e-12) return false;
    const Vec2 w = lms[j] - lms[i];
    sum += lms[i] + (w.x() * dj.y() - w.y() * dj.x()) / den * di;
  }
  *c = sum / 3.0;
  return true;
}

double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

/// P(|x| < a, |y| < a) for (x, y) ~ N(0, C), by Simpson's rule over x.
double boxProbability(const Eigen::Matrix2d& C, double a) {
  const double sx = std::sqrt(C(0, 0)), sy = std::sqrt(C(1, 1));
  if (!(sx > 0) || !(sy > 0)) return 1.0;
  const double rho = C(0, 1) / (sx * sy);
  const double sc = sy * std::sqrt(std::max(1e-300, 1.0 - rho * rho));
  const int n = 400;
  const double h = 2.0 * a / n;
  double sum = 0.0;
  for (int k = 0; k <= n; ++k) {
    const double x = -a + k * h;
    const double pdf = std::exp(-0.5 * x * x / (sx * sx)) / (sx * std::sqrt(2.0 * M_PI));
    const double m = rho * sy / sx * x;
    const double py = normalCdf((a - m) / sc) - normalCdf((-a - m) / sc);
    sum += (k == 0 || k == n ? 1.0 : (k % 2 ? 4.0 : 2.0)) * pdf * py;
  }
  return sum * h / 3.0;
}

void finish(MethodStats& s, double paper_position) {
  const auto n = static_cast<double>(s.pos_errors.size());
  if (n == 0) return;
  std::vector<double> norms, habs, east, north;
  int within = 0;
  for (const auto& e : s.pos_errors) {
    norms.push_back(e.norm());
    east.push_back(e.x());
    north.push_back(e.y());
    s.axis_mean += e / n;
    s.pos_mean += e.norm() / n;
    s.pos_max = std::max(s.pos_max, e.norm());
    within += std::abs(e.x()) < paper_position && std::abs(e.y()) < paper_position;
    s.axis_within_paper += Vec2(std::abs(e.x()) < paper_position, std::abs(e.y()) < paper_position) / n;
  }
  s.axis_rms = Vec2(core::rms(east), core::rms(north));
  s.pos_rms = core::rms(norms);
  s.pos_p95 = core::percentileNearestRank(norms, 0.95);
  s.within_paper = within / n;
  if (s.heading_errors.empty()) return;
  double sh = 0;
  for (double h : s.heading_errors) {
    s.heading_mean += h / n;
    sh += h * h / n;
    habs.push_back(std::abs(h));
  }
  s.heading_rms = core::rms(s.heading_errors);
  s.heading_std = std::sqrt(std::max(0.0, sh - s.heading_mean * s.heading_mean) * n / std::max(1.0, n - 1));
  s.heading_p95 = core::percentileNearestRank(habs, 0.95);
}

const MethodStats& method(const CaseResult& c, const std::string& name) {
  for (const auto& m : c.methods)
    if (m.method == name) return m;
  throw std::logic_error("no method " + name);
}

std::string fmt(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

}  // namespace

std::string readingName(Reading r) { return r == Reading::kFromVehicle ? "from_vehicle" : "apart"; }

std::vector<sim::Landmark> triangleLandmarks(Reading r, double distance) {
  const double R = r == Reading::kFromVehicle ? distance : distance / std::sqrt(3.0);
  std::vector<sim::Landmark> lms;
  for (int i = 0; i < 3; ++i) {
    const double az = i * 2.0 * M_PI / 3.0;  // clockwise from north: N, ESE, WSW
    lms.push_back({i + 1, R * std::sin(az), R * std::cos(az)});
  }
  return lms;
}

Result run(const sim::VisionSensorConfig& vision, const Options& opt) {
  if (opt.runs < 1) throw std::invalid_argument("runs: must be >= 1");
  if (!(opt.distance > 0) || !std::isfinite(opt.distance)) throw std::invalid_argument("distance: must be > 0");
  if (!opt.ins_offset.allFinite() || !std::isfinite(opt.ins_heading_error) || !std::isfinite(opt.true_heading) ||
      !opt.off_centre.allFinite())
    throw std::invalid_argument("INS error, heading and off-centre position must be finite");
  if (opt.off_centre.norm() >= 0.9)
    throw std::invalid_argument("off-centre position must be inside 0.9 circumradius (the danger circle is at 1)");
  Result res;
  res.options = opt;
  res.vision = vision;
  res.sigma_effective = sim::VisionSensor::effectiveStd(vision);
  const int64_t total = 4LL * opt.runs;
  int64_t done = 0;
  const int64_t step = std::max<int64_t>(1, total / 20);
  for (Reading reading : {Reading::kFromVehicle, Reading::kApart}) {
    for (bool centre : {true, false}) {
      CaseResult c;
      c.reading = reading;
      c.centre = centre;
      c.name = readingName(reading) + (centre ? "_centre" : "_off_centre");
      const auto lms = triangleLandmarks(reading, opt.distance);
      c.circumradius = std::hypot(lms[0].x, lms[0].y);
      for (const auto& l : lms) c.landmarks.emplace_back(l.x, l.y);
      c.vehicle = centre ? Vec2::Zero() : Vec2(c.circumradius * opt.off_centre);
      for (int i = 0; i < 3; ++i) c.ranges[i] = (c.landmarks[i] - c.vehicle).norm();
      c.crb = fix::cramerRao(c.vehicle, c.landmarks, res.sigma_effective);
      c.crb_pos_rms = std::sqrt(c.crb(0, 0) + c.crb(1, 1));
      c.crb_heading_std = std::sqrt(c.crb(2, 2));
      c.crb_within_paper = boxProbability(c.crb.topLeftCorner<2, 2>(), opt.paper_position);

      const auto map = sim::landmarkMap(lms);
      fix::FixOptions fo;
      fo.sigma_bearing = res.sigma_effective;
      sim::VisionSensor sensor(vision, lms, sim::componentSeed(opt.seed, "landmark_experiment/" + c.name));
      const double heading_ccw = sim::toFixHeading(opt.true_heading);  // self-inverse
      const Vec2 p_ins = c.vehicle + opt.ins_offset;
      const double psi_ins = core::wrapAngle(opt.true_heading + opt.ins_heading_error);
      c.methods = {MethodStats{}, MethodStats{}, MethodStats{}, MethodStats{}};
      c.methods[0].method = "triangle";
      c.methods[1].method = "least_squares";
      c.methods[2].method = "gauss_newton";
      c.methods[3].method = "uncorrected";
      for (int k = 0; k < opt.runs; ++k) {
        const sim::VisionSample s = sensor.observe(c.vehicle.x(), c.vehicle.y(), heading_ccw, k);
        const auto b = sim::toFixBearings(s);
        const fix::FixResult r[3] = {fix::triangleFix(map, b, p_ins, psi_ins, fo),
                                     fix::leastSquaresFix(map, b, p_ins, psi_ins, fo),
                                     fix::gaussNewtonFix(map, b, p_ins, psi_ins, fo)};
        for (int m = 0; m < 3; ++m) {
          auto& st = c.methods[m];
          if (!r[m].ok) {
            if (st.refused++ == 0) st.first_refusal = r[m].error;
            continue;
          }
          ++st.ok;
          st.pos_errors.push_back(r[m].position - c.vehicle);
          st.heading_errors.push_back(core::wrapAngle(r[m].heading - opt.true_heading));
        }
        if (k == 0) c.condition = r[1].condition;
        // Uncorrected: centroid of the error triangle drawn with the INS heading.
        auto& un = c.methods[3];
        double az[3];
        Vec2 cen;
        bool ok = b.size() == 3;
        if (ok) {
          std::vector<Vec2> l3;
          for (int i = 0; i < 3; ++i) {
            l3.push_back(map.at(b[i].landmark_id));
            az[i] = psi_ins + b[i].alpha;
          }
          ok = triangleCentroid(l3, az, &cen);
        }
        if (!ok) {
          if (un.refused++ == 0) un.first_refusal = b.size() == 3 ? "azimuth lines are parallel" : "not three bearings";
        } else {
          ++un.ok;
          un.pos_errors.push_back(cen - c.vehicle);
        }
        ++done;
        if (opt.progress && (done % step == 0 || done == total)) opt.progress(done, total);
      }
      for (auto& m : c.methods) finish(m, opt.paper_position);
      res.cases.push_back(std::move(c));
    }
  }
  // Which reading the paper's position figure fits (centre cases, least squares).
  std::vector<std::string> fits;
  for (const auto& c : res.cases)
    if (c.centre && method(c, "least_squares").within_paper >= 0.5) fits.push_back(readingName(c.reading));
  res.position_fit = fits.size() == 1 ? fits[0] : fits.empty() ? "neither" : "both";
  const CaseResult* apart = nullptr;
  const CaseResult* from = nullptr;
  for (const auto& c : res.cases)
    if (c.centre) (c.reading == Reading::kApart ? apart : from) = &c;
  const auto& la = method(*apart, "least_squares");
  const auto& lf = method(*from, "least_squares");
  const double h2 = 2.0 * la.heading_std;
  res.implied_bearing_std = h2 > 0 ? res.sigma_effective * opt.paper_heading_2sigma / h2 : 0.0;
  std::ostringstream os;
  os << "Position: with both axis errors below " << opt.paper_position << " m in "
     << fmt("%.0f", 100 * lf.within_paper) << " % of runs (landmarks " << opt.distance << " m from the vehicle) and "
     << fmt("%.0f", 100 * la.within_paper) << " % (landmarks " << opt.distance
     << " m apart), the paper's \"mostly less than " << opt.paper_position << " m\" fits ";
  if (res.position_fit == "apart")
    os << "the reading 'landmarks " << opt.distance << " m apart'.";
  else if (res.position_fit == "from_vehicle")
    os << "the reading 'landmarks " << opt.distance << " m from the vehicle'.";
  else
    os << res.position_fit << " reading.";
  os << " Heading: measured 2 sigma " << fmt("%.1f", 2 * la.heading_std * kAs) << "\" (apart) and "
     << fmt("%.1f", 2 * lf.heading_std * kAs) << "\" (from vehicle) against the Cramér-Rao bound "
     << fmt("%.1f", 2 * apart->crb_heading_std * kAs) << "\", which does not depend on the size of the triangle; "
     << "the paper's " << fmt("%.0f", opt.paper_heading_2sigma * kAs) << "\" fits neither reading: it is below the bound "
     << "and would need about " << fmt("%.1f", res.implied_bearing_std * kAs) << "\" (1 sigma) bearing noise.";
  res.conclusion = os.str();
  return res;
}

Result runObservations(const std::vector<sim::Landmark>& lms, const std::vector<Observation>& obs,
                       const Options& opt) {
  if (obs.empty()) throw std::invalid_argument("no observations");
  const auto map = sim::landmarkMap(lms);
  Result res;
  res.options = opt;
  res.options.runs = static_cast<int>(obs.size());
  res.sigma_effective = obs.front().sample.bearing_std;
  res.vision.bearing_std = res.sigma_effective;
  res.vision.resolution = 0.0;
  if (!(res.sigma_effective > 0)) throw std::invalid_argument("observations carry no bearing_std");
  CaseResult c;
  c.name = "log";
  c.centre = false;
  for (const auto& l : lms) c.landmarks.emplace_back(l.x, l.y);
  c.methods = {MethodStats{}, MethodStats{}};
  c.methods[0].method = "triangle";
  c.methods[1].method = "least_squares";
  fix::FixOptions fo;
  fo.sigma_bearing = res.sigma_effective;
  Eigen::Matrix3d crb_sum = Eigen::Matrix3d::Zero();
  int n_crb = 0;
  Vec2 mean_pos = Vec2::Zero();
  for (std::size_t k = 0; k < obs.size(); ++k) {
    const auto& o = obs[k];
    const Vec2 p(o.x, o.y);
    const double psi = sim::toFixHeading(o.heading);
    const auto b = sim::toFixBearings(o.sample);
    const fix::FixResult r[2] = {fix::triangleFix(map, b, p + opt.ins_offset, psi + opt.ins_heading_error, fo),
                                 fix::leastSquaresFix(map, b, p + opt.ins_offset, psi + opt.ins_heading_error, fo)};
    for (int m = 0; m < 2; ++m) {
      auto& st = c.methods[m];
      if (!r[m].ok) {
        if (st.refused++ == 0) st.first_refusal = r[m].error;
        continue;
      }
      ++st.ok;
      st.pos_errors.push_back(r[m].position - p);
      st.heading_errors.push_back(core::wrapAngle(r[m].heading - psi));
    }
    if (r[1].ok) {
      std::vector<Vec2> l3;
      for (const auto& x : b) l3.push_back(map.at(x.landmark_id));
      crb_sum += fix::cramerRao(p, l3, res.sigma_effective);
      mean_pos += p;
      c.condition = std::max(c.condition, r[1].condition);
      ++n_crb;
    }
    if (opt.progress) opt.progress(static_cast<int64_t>(k + 1), static_cast<int64_t>(obs.size()));
  }
  for (auto& m : c.methods) finish(m, opt.paper_position);
  if (n_crb > 0) {
    c.crb = crb_sum / n_crb;
    c.vehicle = mean_pos / n_crb;
    c.crb_pos_rms = std::sqrt(c.crb(0, 0) + c.crb(1, 1));
    c.crb_heading_std = std::sqrt(c.crb(2, 2));
    c.crb_within_paper = boxProbability(c.crb.topLeftCorner<2, 2>(), opt.paper_position);
    for (int i = 0; i < 3 && i < static_cast<int>(c.landmarks.size()); ++i)
      c.ranges[i] = (c.landmarks[i] - c.vehicle).norm();
  }
  const auto& ls = c.methods[1];
  std::ostringstream os;
  os << obs.size() << " recorded observations, " << ls.ok << " fixed: position RMS " << fmt("%.3f", ls.pos_rms)
     << " m (bound " << fmt("%.3f", c.crb_pos_rms) << " m), heading 2 sigma " << fmt("%.1f", 2 * ls.heading_std * kAs)
     << "\" (bound " << fmt("%.1f", 2 * c.crb_heading_std * kAs) << "\").";
  res.conclusion = os.str();
  res.position_fit = "n/a";
  res.cases.push_back(std::move(c));
  return res;
}

std::string summaryTable(const Result& r) {
  std::ostringstream os;
  os << "runs " << r.options.runs << ", seed " << r.options.seed << ", bearing noise "
     << fmt("%.1f", r.vision.bearing_std * kAs) << "\" resolution " << fmt("%.1f", r.vision.resolution * kAs)
     << "\" (effective " << fmt("%.2f", r.sigma_effective * kAs) << "\")\n";
  char line[320];
  std::snprintf(line, sizeof line, "%-24s %-14s %6s %6s %8s %8s %8s %8s %9s %8s %9s %9s %8s\n", "case", "method",
                "ok", "refus", "mean[m]", "rms[m]", "p95[m]", "max[m]", "<0.1m[%]", "h_mean\"", "h_2sig\"", "rms/CRB",
                "h/CRB");
  os << line;
  for (const auto& c : r.cases) {
    for (const auto& m : c.methods) {
      if (m.ok == 0) {
        std::snprintf(line, sizeof line, "%-24s %-14s %6d %6d   (all refused: %s)\n", c.name.c_str(),
                      m.method.c_str(), m.ok, m.refused, m.first_refusal.c_str());
        os << line;
        continue;
      }
      const bool h = m.method != "uncorrected";
      std::snprintf(line, sizeof line, "%-24s %-14s %6d %6d %8.4f %8.4f %8.4f %8.4f %9.1f %8s %9s %9.3f %8s\n",
                    c.name.c_str(), m.method.c_str(), m.ok, m.refused, m.pos_mean, m.pos_rms, m.pos_p95, m.pos_max,
                    100 * m.within_paper, h ? fmt("%.2f", m.heading_mean * kAs).c_str() : "-",
                    h ? fmt("%.2f", 2 * m.heading_std * kAs).c_str() : "-", m.pos_rms / c.crb_pos_rms,
                    h ? fmt("%.3f", m.heading_std / c.crb_heading_std).c_str() : "-");
      os << line;
    }
    std::snprintf(line, sizeof line, "%-24s %-14s %6s %6s %8s %8.4f %8s %8s %9.1f %8s %9.2f   (range %.0f m, cond %.1f)\n",
                  c.name.c_str(), "CRB", "", "", "", c.crb_pos_rms, "", "", 100 * c.crb_within_paper, "",
                  2 * c.crb_heading_std * kAs, c.ranges[0], c.condition);
    os << line;
  }
  os << "paper (§III): position per axis mostly < " << r.options.paper_position << " m, heading "
     << fmt("%.0f", r.options.paper_heading_2sigma * kAs) << "\" (2 sigma)\n"
     << r.conclusion << "\n";
  return os.str();
}

bool writeReport(const Result& r, const std::string& dir) {
  namespace fs = std::filesystem;
  using nlohmann::json;
  fs::create_directories(dir);
  const auto& o = r.options;
  json j;
  j["paper"] = {{"source", "seeds/004 §III, Fig. 5"},
                {"position_per_axis_m", o.paper_position},
                {"heading_2sigma_arcsec", o.paper_heading_2sigma * kAs}};
  j["options"] = {{"runs", o.runs},
                  {"seed", o.seed},
                  {"distance_m", o.distance},
                  {"ins_offset_m", {o.ins_offset.x(), o.ins_offset.y()}},
                  {"ins_heading_error_arcmin", o.ins_heading_error * kAs / 60.0},
                  {"true_heading_rad", o.true_heading},
                  {"off_centre_fraction", {o.off_centre.x(), o.off_centre.y()}}};
  j["vision"] = {{"bearing_std_arcsec", r.vision.bearing_std * kAs},
                 {"resolution_arcsec", r.vision.resolution * kAs},
                 {"effective_std_arcsec", r.sigma_effective * kAs}};
  j["position_fit"] = r.position_fit;
  j["implied_bearing_std_arcsec"] = r.implied_bearing_std * kAs;
  j["conclusion"] = r.conclusion;
  json cases = json::array();
  for (const auto& c : r.cases) {
    json jc;
    jc["name"] = c.name;
    jc["reading"] = readingName(c.reading);
    jc["centre"] = c.centre;
    jc["circumradius_m"] = c.circumradius;
    jc["vehicle_m"] = {c.vehicle.x(), c.vehicle.y()};
    jc["landmarks_m"] = json::array();
    for (const auto& l : c.landmarks) jc["landmarks_m"].push_back({l.x(), l.y()});
    jc["ranges_m"] = {c.ranges[0], c.ranges[1], c.ranges[2]};
    jc["crb"] = {{"position_rms_m", c.crb_pos_rms},
                 {"east_std_m", std::sqrt(c.crb(0, 0))},
                 {"north_std_m", std::sqrt(c.crb(1, 1))},
                 {"heading_std_arcsec", c.crb_heading_std * kAs},
                 {"heading_2sigma_arcsec", 2 * c.crb_heading_std * kAs},
                 {"within_paper_fraction", c.crb_within_paper}};
    for (const auto& m : c.methods) {
      json jm = {{"ok", m.ok},
                 {"refused", m.refused},
                 {"position_mean_m", m.pos_mean},
                 {"position_rms_m", m.pos_rms},
                 {"position_p95_m", m.pos_p95},
                 {"position_max_m", m.pos_max},
                 {"east_mean_m", m.axis_mean.x()},
                 {"north_mean_m", m.axis_mean.y()},
                 {"east_rms_m", m.axis_rms.x()},
                 {"north_rms_m", m.axis_rms.y()},
                 {"within_paper_fraction", m.within_paper},
                 {"east_within_paper_fraction", m.axis_within_paper.x()},
                 {"north_within_paper_fraction", m.axis_within_paper.y()},
                 {"position_rms_over_crb", c.crb_pos_rms > 0 ? m.pos_rms / c.crb_pos_rms : 0.0}};
      if (!m.first_refusal.empty()) jm["first_refusal"] = m.first_refusal;
      if (m.method != "uncorrected")
        jm.update({{"heading_mean_arcsec", m.heading_mean * kAs},
                   {"heading_std_arcsec", m.heading_std * kAs},
                   {"heading_2sigma_arcsec", 2 * m.heading_std * kAs},
                   {"heading_rms_arcsec", m.heading_rms * kAs},
                   {"heading_p95_abs_arcsec", m.heading_p95 * kAs},
                   {"heading_std_over_crb", c.crb_heading_std > 0 ? m.heading_std / c.crb_heading_std : 0.0}});
      jc["methods"][m.method] = jm;
    }
    cases.push_back(jc);
  }
  j["cases"] = cases;
  eval::writeJson(j, dir + "/report.json");

  // Data files and one figure per case: position errors with the CRB 95 % ellipse and the
  // paper's +-0.1 m box; histogram of heading errors with the CRB 2 sigma and the paper's 20".
  std::ofstream gp(dir + "/plot.gp");
  gp << "set terminal pngcairo size 1400,650 noenhanced\n";
  for (const auto& c : r.cases) {
    const auto& t = method(c, "triangle");
    const auto& l = method(c, "least_squares");
    {
      std::ofstream f(dir + "/" + c.name + "_errors.dat");
      f << "# run  triangle: east north [m] heading [arcsec]  least_squares: east north heading\n";
      const std::size_t n = std::min(t.pos_errors.size(), l.pos_errors.size());
      for (std::size_t k = 0; k < n; ++k)
        f << k << ' ' << t.pos_errors[k].x() << ' ' << t.pos_errors[k].y() << ' ' << t.heading_errors[k] * kAs << ' '
          << l.pos_errors[k].x() << ' ' << l.pos_errors[k].y() << ' ' << l.heading_errors[k] * kAs << '\n';
    }
    {
      // 95 % ellipse of N(0, CRB position block): chi-square 2 dof, 5.991.
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(c.crb.topLeftCorner<2, 2>());
      const Eigen::Matrix2d A = es.eigenvectors() * es.eigenvalues().cwiseMax(0).cwiseSqrt().asDiagonal();
      std::ofstream f(dir + "/" + c.name + "_crb_ellipse.dat");
      for (int k = 0; k <= 180; ++k) {
        const double a = 2.0 * M_PI * k / 180.0;
        const Vec2 p = std::sqrt(5.991) * A * Vec2(std::cos(a), std::sin(a));
        f << p.x() << ' ' << p.y() << '\n';
      }
    }
    double hmax = std::max(2 * c.crb_heading_std, o.paper_heading_2sigma) * kAs;
    for (double h : l.heading_errors) hmax = std::max(hmax, std::abs(h) * kAs);
    for (double h : t.heading_errors) hmax = std::max(hmax, std::abs(h) * kAs);
    hmax *= 1.05;
    // An odd number of bins: zero is a bin centre (the quantized errors often sit on zero).
    const int nb = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(l.heading_errors.size()))), 10,
                              std::max(10, o.histogram_bins)) | 1;
    const double w = 2.0 * hmax / nb;
    {
      std::vector<int> ht(nb, 0), hl(nb, 0);
      auto bin = [&](double h) { return std::clamp(static_cast<int>(std::floor((h * kAs + hmax) / w)), 0, nb - 1); };
      for (double h : t.heading_errors) ++ht[bin(h)];
      for (double h : l.heading_errors) ++hl[bin(h)];
      std::ofstream f(dir + "/" + c.name + "_heading_hist.dat");
      f << "# bin centre [arcsec]  triangle  least_squares (counts)\n";
      for (int k = 0; k < nb; ++k) f << -hmax + (k + 0.5) * w << ' ' << ht[k] << ' ' << hl[k] << '\n';
    }
    const double c2 = 2 * c.crb_heading_std * kAs, p2 = o.paper_heading_2sigma * kAs, pp = o.paper_position;
    std::string title = "Fig. 5 (" + c.name + "): " + std::to_string(o.runs);
    if (c.name == "log")
      title += " recorded observations, CRB at their mean";
    else
      title += std::string(" runs, landmarks ") + (c.reading == Reading::kApart ? "" : "at ") + fmt("%g", o.distance) +
               " m " + (c.reading == Reading::kApart ? "apart" : "from the centre") +
               (c.centre ? ", vehicle at the centre" : ", vehicle off centre");
    gp << "set output '" << c.name << ".png'\n"
       << "set multiplot layout 1,2 title '" << title << "'\n"
       << "set grid\nset size ratio -1\nset xlabel 'east error [m]'\nset ylabel 'north error [m]'\nset key below horizontal\n"
       << "set title 'position error'\n"
       << "set object 1 rect from " << -pp << "," << -pp << " to " << pp << "," << pp
       << " fs empty border lc rgb '#888888' dt 2\n"
       << "plot '" << c.name << "_errors.dat' using 2:3 with points pt 7 ps 0.4 lc rgb '#1f77b4' title 'error triangle', "
       << "'' using 5:6 with points pt 6 ps 0.6 lc rgb '#d62728' title 'least squares', "
       << "'" << c.name << "_crb_ellipse.dat' using 1:2 with lines lw 2 lc rgb 'black' title 'CRB 95 %', "
       << "NaN with lines dt 2 lc rgb '#888888' title 'paper +-" << pp << " m'\n"
       << "unset object 1\nset size noratio\nset title 'heading error'\nset xlabel 'heading error [arcsec]'\n"
       << "set ylabel 'runs'\nset style fill transparent solid 0.4\nset key below horizontal\n"
       << "set arrow 1 from " << -c2 << ", graph 0 to " << -c2 << ", graph 1 nohead lw 2 lc rgb 'black'\n"
       << "set arrow 2 from " << c2 << ", graph 0 to " << c2 << ", graph 1 nohead lw 2 lc rgb 'black'\n"
       << "set arrow 3 from " << -p2 << ", graph 0 to " << -p2 << ", graph 1 nohead dt 2 lw 2 lc rgb '#2ca02c'\n"
       << "set arrow 4 from " << p2 << ", graph 0 to " << p2 << ", graph 1 nohead dt 2 lw 2 lc rgb '#2ca02c'\n"
       << "plot '" << c.name << "_heading_hist.dat' using 1:2:(" << w << ") with boxes lc rgb '#1f77b4' title 'error triangle', "
       << "'' using 1:3:(" << w << ") with boxes fs empty lw 2 lc rgb '#d62728' title 'least squares', "
       << "NaN with lines lw 2 lc rgb 'black' title 'CRB 2 sigma', "
       << "NaN with lines dt 2 lw 2 lc rgb '#2ca02c' title 'paper 2 sigma'\n"
       << "unset arrow\nunset multiplot\n";
  }
  gp.close();
  return eval::runGnuplot(dir, "plot.gp") == 0;
}

}  // namespace lcmloc::landmark_experiment
