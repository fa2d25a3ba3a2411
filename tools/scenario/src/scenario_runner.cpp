// In-process scenario: world + sensors stepped in the driver processes' order, feeding one
// FusionEngine per filter config, then metrics against ground truth.
#include "lcmloc/scenario/scenario_runner.hpp"

#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/scoring.hpp"

namespace lcmloc::scenario {
namespace {

using namespace sim;

const char* const kOdometryChannel = "ODOMETRY";
const char* const kRulerChannel = "MAGRULER";
const char* const kFaultChannel = "MAGRULER_FAULT";
const char* const kImuChannel = "IMU";
const char* const kGpsChannel = "GPS";
constexpr long kMaxSteps = 10'000'000;  // guards against a vehicle that never arrives

struct FilterRun {
  ScenarioFilterResult result;
  std::vector<core::FilterState> states;  // one per distinct utime, last state wins
  bool ever_lockout_status = false;
  std::unique_ptr<core::FusionEngine> engine;
};

core::EngineOutputs outputsFor(FilterRun* run) {
  core::EngineOutputs out;
  out.on_state = [run](const std::string&, bool is_active, const core::FilterState& s) {
    if (!is_active) return;
    if (s.status == core::FilterStatus::Lockout) run->ever_lockout_status = true;
    if (!run->states.empty() && run->states.back().utime == s.utime)
      run->states.back() = s;
    else
      run->states.push_back(s);
  };
  out.on_decision = [run](const std::string&, bool is_active, const core::GateDecision& d) {
    if (!is_active) return;
    run->result.decisions.push_back(d);
    run->result.decision_is_fault.push_back(d.sensor == kFaultChannel);  // GPS/IMU: never a fault
  };
  out.on_event = [run](const core::EngineEvent& e) {
    if (e.kind == core::EventKind::Lockout) ++run->result.lockout_events;
  };
  return out;
}

std::optional<double> nees(const core::FilterState& s, const TruthState& t) {
  const Eigen::Vector3d e(s.x(0) - t.x, s.x(1) - t.y, core::wrapAngle(s.x(2) - t.heading));
  return core::nees<3>(e, s.P.topLeftCorner<3, 3>());
}

void computeMetrics(FilterRun& run, const std::vector<TruthState>& truth, int64_t t0,
                    int64_t period_us, int lockout_rejections) {
  ScenarioFilterResult& r = run.result;
  std::vector<double> errors, nees_values;
  for (const auto& s : run.states) {
    const int64_t k = (s.utime - t0) / period_us;
    if (k < 0 || k >= static_cast<int64_t>(truth.size()) || truth[k].utime != s.utime) continue;
    const TruthState& t = truth[k];
    TrackPoint p;
    p.utime = s.utime;
    p.truth = core::Pose(t.x, t.y, t.heading);
    p.estimate = s;
    r.track.push_back(p);
    errors.push_back(std::hypot(s.x(0) - t.x, s.x(1) - t.y));
    const auto n = nees(s, t);
    if (n && std::isfinite(*n)) nees_values.push_back(*n);
  }
  const auto e = core::errorStats(errors);
  r.rmse_m = e.rmse;
  r.max_error_m = e.max;
  if (!errors.empty()) r.final_error_m = errors.back();
  if (!nees_values.empty()) r.mean_nees = core::errorStats(nees_values).mean;

  core::FaultCounts counts;
  int trailing_gate_rejections = 0;
  for (std::size_t i = 0; i < r.decisions.size(); ++i) {
    const auto& d = r.decisions[i];
    const bool fault = r.decision_is_fault[i];
    core::countDecision(counts, d.accepted, d.reason, fault);
    if (!fault && !core::isIgnoredDecision(d.reason))
      trailing_gate_rejections = (!d.accepted && d.reason == "gate") ? trailing_gate_rejections + 1 : 0;
  }
  r.faults_total = counts.faults_decided;
  r.faults_rejected = counts.faults_rejected;
  r.valid_rejected = counts.valid_rejected;
  r.accepted = counts.accepted;
  r.rejected = counts.rejected;
  r.locked_out = run.ever_lockout_status || r.lockout_events > 0 ||
                 (lockout_rejections > 0 && trailing_gate_rejections >= lockout_rejections);
}

}  // namespace

ScenarioResult runScenario(const ScenarioConfig& sc, const std::vector<core::FilterConfig>& filters,
                           int output_every) {
  ScenarioResult res;
  const Path path(sc.path);
  res.map = makeMarkerMap(path, sc.markers);
  const double stop_at = stopArcLength(sc, path.length());
  VehicleSim vehicle(sc.vehicle, path, stop_at, componentSeed(sc.seed, "vehicle"));
  ImuSensor imu(sc.imu, sc.vehicle.wheelbase, componentSeed(sc.seed, "imu"));
  GpsSensor gps(sc.gps, componentSeed(sc.seed, "gps"));
  OdometrySensor odometry(sc.odometry, sc.vehicle.wheelbase, componentSeed(sc.seed, "odometry"));
  MagneticRuler ruler(sc.magruler, res.map, componentSeed(sc.seed, "magruler"));
  FaultInjector faults(sc.faults, sc.magruler, componentSeed(sc.seed, "faults"));

  std::vector<std::unique_ptr<FilterRun>> runs;
  for (const auto& fc : filters) {
    auto run = std::make_unique<FilterRun>();
    run->result.filter = fc.type;
    core::EngineConfig ec;
    ec.filter = fc;
    ec.output_every = output_every;
    run->engine = std::make_unique<core::FusionEngine>(ec, res.map, outputsFor(run.get()));
    runs.push_back(std::move(run));
  }
  auto feed = [&runs](const core::EngineInput& in) {
    for (auto& run : runs) run->engine->push(in);
  };

  int64_t odo_seq = 0, ruler_seq = 0, fault_seq = 0, imu_seq = 0, gps_seq = 0;
  auto process = [&](const TruthState& t) {
    res.truth.push_back(t);
    if (auto o = odometry.sample(t)) feed({kOdometryChannel, odo_seq++, o->input.utime, o->input});
    if (auto r = ruler.sample(t)) {
      const int64_t seq = ruler_seq++;
      if (r->detected)
        feed({kRulerChannel, seq, r->utime,
              core::RulerDetection{r->utime, r->lateral_offset, r->quality, kRulerChannel, seq}});
    }
    if (sc.imu.enabled)
      if (auto m = imu.sample(t)) {
        const int64_t seq = imu_seq++;
        feed({kImuChannel, seq, m->utime, m->input(kImuChannel, seq)});
      }
    if (sc.gps.enabled)
      if (auto g = gps.sample(t)) {
        const int64_t seq = gps_seq++;
        res.gps.push_back(*g);
        feed({kGpsChannel, seq, g->utime,
              core::GpsInput{g->utime, g->has_fix, g->x, g->y, g->position_std, kGpsChannel, seq}});
      }
    if (auto f = faults.sample(t)) {
      const int64_t seq = fault_seq++;
      const RulerReading& r = f->reading;
      feed({kFaultChannel, seq, r.utime,
            core::RulerDetection{r.utime, r.lateral_offset, r.quality, kFaultChannel, seq}});
    }
  };
  process(vehicle.state());
  for (long i = 0; !vehicle.finished(); ++i) {
    if (i >= kMaxSteps) throw std::runtime_error("runScenario: the vehicle never reached the end");
    process(vehicle.step());
  }
  for (auto& run : runs) run->engine->flush();

  const auto period_us = static_cast<int64_t>(std::llround(1e6 / sc.vehicle.rate_hz));
  for (std::size_t i = 0; i < runs.size(); ++i) {
    computeMetrics(*runs[i], res.truth, sc.vehicle.start_utime, period_us,
                   filters[i].lockout_rejections);
    res.filters.push_back(std::move(runs[i]->result));
  }
  return res;
}

}  // namespace lcmloc::scenario
