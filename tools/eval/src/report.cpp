#include "lcmloc/eval/report.hpp"

#include "lcmloc/eval/gnuplot.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <stdexcept>

namespace lcmloc::eval {
namespace {

using nlohmann::json;

/// JSON has no infinity or NaN: such values become null.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json metricsJson(const Metrics& m) {
  const bool scored = m.samples > 0;  // no error is not a perfect score
  return {{"rmse_m", scored ? json(m.rmse_m) : json(nullptr)},
          {"max_error_m", scored ? json(m.max_error_m) : json(nullptr)},
          {"final_error_m", scored ? json(m.final_error_m) : json(nullptr)},
          {"samples", m.samples},
          {"accepted", m.accepted},
          {"rejected", m.rejected},
          {"ignored", m.ignored},
          {"faults_total", m.faults_total},
          {"faults_rejected", m.faults_rejected},
          {"faults_accepted", m.faults_accepted},
          {"valid_rejected", m.valid_rejected},
          {"lockouts", m.lockouts}};
}

json measurementsJson(const FilterRun& run, int64_t t0) {
  json list = json::array();
  for (const auto& r : run.decisions) {
    const auto& d = r.decision;
    list.push_back({{"utime", d.utime},
                    {"t_s", secondsSince(d.utime, t0)},
                    {"sensor", d.sensor},
                    {"measurement_seq", d.measurement_seq},
                    {"innovation_distance", number(d.mahalanobis)},
                    {"gate", number(d.gate)},
                    {"accepted", d.accepted},
                    {"reason", d.reason},
                    {"marker_id", d.marker_id},
                    {"fault", r.is_fault}});
  }
  return list;
}

json filterJson(const FilterRun& run, int64_t t0) {
  json j = metricsJson(run.metrics);
  j["measurements"] = measurementsJson(run, t0);
  return j;
}

json logJson(const LogData& data) {
  json issues = json::array();
  for (const auto& i : data.issues)
    issues.push_back({{"event_index", i.event_index}, {"byte_offset", i.byte_offset}, {"what", i.what}});
  return {{"path", data.path},
          {"file_size", data.file_size},
          {"events_read", data.events_read},
          {"bytes_unreadable", data.bytes_unreadable},
          {"damaged", data.damaged},
          {"interrupted", data.interrupted},
          {"channels", data.channel_counts},
          {"odometry_messages", data.odometry_messages},
          {"ruler_messages", data.ruler_messages},
          {"ruler_detections", data.ruler_detections},
          {"truth_samples", data.truth.size()},
          {"bad_utime", data.bad_utime},
          {"issues", issues}};
}

void row(std::ostream& os, const std::string& name, const Metrics& m) {
  os << std::left << std::setw(22) << withoutControlCharacters(name) << std::right << std::fixed << std::setprecision(3);
  if (m.samples > 0)
    os << std::setw(9) << m.rmse_m << std::setw(9) << m.max_error_m << std::setw(10) << m.final_error_m;
  else
    os << std::setw(9) << "-" << std::setw(9) << "-" << std::setw(10) << "-";
  if (m.ignored > 0 && m.accepted + m.rejected == 0) {  // dead reckoning: uses no ruler data
    os << std::setw(10) << "-" << std::setw(10) << "-" << std::setw(8)
       << ("-/" + std::to_string(m.faults_total)) << std::setw(11) << "-" << "\n";
    return;
  }
  os << std::setw(10) << m.accepted << std::setw(10) << m.rejected << std::setw(8)
     << (std::to_string(m.faults_rejected) + "/" + std::to_string(m.faults_total)) << std::setw(11)
     << m.valid_rejected << "\n";
}

}  // namespace

json makeReport(const LogData& data, const Evaluation& ev, const ReportMeta& meta) {
  json j;
  j["log"] = logJson(data);
  j["config"] = meta.config_file;
  j["gate_threshold"] = ev.gate_threshold;
  j["gate"] = {{"threshold", ev.gate_threshold},
               {"probability", meta.gate.probability},
               {"dof", meta.gate.dof == 0 ? 2 : meta.gate.dof},
               {"value", meta.gate.value ? json(*meta.gate.value) : json(nullptr)}};
  json faults = json::array();
  for (const auto& f : ev.faults)
    faults.push_back({{"utime", f.fault.utime},
                      {"kind", f.fault.kind},
                      {"channel", f.fault.channel},
                      {"measurement_seq", f.fault.measurement_seq},
                      {"x", f.fault.x},
                      {"y", f.fault.y},
                      {"lateral_offset", f.fault.lateral_offset}});
  j["faults"] = faults;
  j["filters"] = json::object();
  for (const auto& run : ev.filters) j["filters"][run.name] = filterJson(run, ev.t0_utime);
  if (ev.live) {
    json live = filterJson(ev.live->run, ev.t0_utime);
    live["filter"] = ev.live->filter;
    live["poses"] = ev.live->run.track.size();
    live["matched_poses"] = ev.live->matched_poses;
    live["max_diff_to_replay_m"] = ev.live->max_diff_to_replay_m >= 0 ? json(ev.live->max_diff_to_replay_m) : json(nullptr);
    j["live"] = live;
  } else {
    j["live"] = nullptr;
  }
  return j;
}

void writeJson(const json& report, const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write '" + path + "'");
  // Strings from a log (channel, filter and sensor names) may hold any bytes: invalid UTF-8 is
  // written as U+FFFD rather than failing the whole report.
  f << report.dump(2, ' ', false, json::error_handler_t::replace) << "\n";
  if (!f) throw std::runtime_error("error while writing '" + path + "'");
}

void printSummary(std::ostream& os, const LogData& data, const Evaluation& ev) {
  os << std::left << std::setw(22) << "filter" << std::right << std::setw(9) << "RMSE[m]"
     << std::setw(9) << "max[m]" << std::setw(10) << "final[m]" << std::setw(10) << "accepted"
     << std::setw(10) << "rejected" << std::setw(8) << "faults" << std::setw(11) << "valid_rej"
     << "\n";
  std::vector<const FilterRun*> runs;
  for (const auto& run : ev.filters) runs.push_back(&run);
  if (ev.live) runs.push_back(&ev.live->run);
  for (const auto* run : runs) row(os, run->name, run->metrics);
  os << "faults = rejected/total (- = filter does not use the ruler); gate threshold " << std::setprecision(3) << ev.gate_threshold
     << " (innovation distance, 2-dof chi-square)\n";
  if (ev.live && ev.live->max_diff_to_replay_m >= 0)
    os << "live " << withoutControlCharacters(ev.live->filter) << " vs offline replay: max position difference "
       << std::scientific << std::setprecision(2) << ev.live->max_diff_to_replay_m << " m over "
       << ev.live->matched_poses << " poses\n" << std::fixed;
  if (data.truth.empty()) os << "no ground truth in the log: errors not computed\n";
  else
    for (const auto* run : runs)
      if (run->metrics.samples == 0)
        os << "warning: " << withoutControlCharacters(run->name) << ": no estimate within 0.1 s of the ground truth's time span: errors not "
              "computed\n";
  os << "log: " << data.events_read << " events, " << data.file_size << " bytes";
  if (data.damaged) os << ", DAMAGED (" << data.bytes_unreadable << " bytes unreadable)";
  os << ", " << data.issues.size() << " issue(s)\n";
  printIssues(os, data.issues);
  printBadUtime(os, data.bad_utime);
}

}  // namespace lcmloc::eval
