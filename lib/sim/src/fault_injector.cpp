// Fault-marker injector: a detection that is wrong (phantom magnet, wrong offset), with the
// readings the physical ruler would show for a single marker at the reported offset.
#include <algorithm>
#include <stdexcept>

#include "lcmloc/sim/world.hpp"

namespace lcmloc::sim {

FaultInjector::FaultInjector(std::vector<FaultConfig> faults, const MagRulerConfig& ruler,
                             uint64_t seed)
    : faults_(std::move(faults)), ruler_(ruler), rng_(seed),
      mapper_(std::make_shared<MagneticRuler>(ruler, core::MarkerMap{}, seed)) {
  for (const auto& f : faults_)
    if (f.kind != "phantom_marker" && f.kind != "wrong_offset")
      throw std::invalid_argument("faults.kind: unknown kind '" + f.kind +
                                  "' (phantom_marker or wrong_offset)");
  std::stable_sort(faults_.begin(), faults_.end(), [](const FaultConfig& a, const FaultConfig& b) {
    return a.at_distance < b.at_distance;
  });
}

std::optional<InjectedFault> FaultInjector::sample(const TruthState& truth) {
  // Written so that a NaN distance (corrupt ground truth) fires nothing: `distance < at` is
  // false for NaN, and the fault went off at once, at the wrong place.
  if (next_ >= faults_.size() || !(truth.distance >= faults_[next_].at_distance)) return std::nullopt;
  InjectedFault out;
  out.fault = faults_[next_++];
  out.truth = truth;
  std::normal_distribution<double> noise(0.0, ruler_.noise_std);
  RulerReading& r = out.reading;
  r.utime = truth.utime;
  r.readings = singleMarkerReadings(ruler_, 0.0, out.fault.lateral_offset);
  for (double& v : r.readings) v += noise(rng_);
  r.detected = true;
  r.lateral_offset = mapper_->peakMap(r.readings).value_or(out.fault.lateral_offset);
  r.quality = 1.0;
  return out;
}

}  // namespace lcmloc::sim
