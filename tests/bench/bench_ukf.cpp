// One UKF predict + one range-bearing update for the 3-state model of the magnetic-ruler paper.
//   BM_UkfPredictUpdate:    the fixed-size kernel (lcmloc::core::Ukf<3>) with eq. 1-2 and eq. 5.
//   BM_FilterPredictUpdate: the same step through the Filter interface ("ukf_gated"), including
//                           association over a 20-marker map, the gate and the GateDecision.
//   BM_ModelCallsOnly:      the 7 process-model and 7 measurement-model calls of one step alone
//                           (sin/cos, atan2, sqrt): the floor no UKF can go below; compare the
//                           kernel's median with it in the same run on a shared machine.
// Run: bench_ukf --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/ruler_model.hpp"
#include "lcmloc/core/ukf.hpp"
#include "lcmloc/core/vehicle_model.hpp"

namespace {

using namespace lcmloc::core;

constexpr double kWheelbase = 2.5, kL1 = 1.5;

void BM_UkfPredictUpdate(benchmark::State& state) {
  Ukf<3> ukf(SigmaParams{1.0, 0.0, 0.0}, 1u << 2);
  const Vec3 x0(0.0, 0.0, 1.5707963267948966);
  const Mat3 P0 = Vec3(1e-2, 1e-2, 1e-2).asDiagonal();
  const Mat3 Q = Vec3(1e-6, 1e-6, 8.73e-5).asDiagonal();
  const Mat2 R = Vec2(1e-4, 3.1e-4).asDiagonal();
  const double ds = 0.015, psi = 0.05;
  // A marker 5 cm left of the ruler centre once the vehicle has moved ds.
  const Pose moved = propagatePose(x0, ds, headingIncrement(ds, psi, kWheelbase));
  const double xm = moved.x() + kL1 * std::cos(moved.z()) - 0.05 * std::sin(moved.z());
  const double ym = moved.y() + kL1 * std::sin(moved.z()) + 0.05 * std::cos(moved.z());
  const Vec2 z = rulerObservation(0.05, kL1);
  const double dth = headingIncrement(ds, psi, kWheelbase);  // eq. 2 does not depend on the state
  auto f = [&](const Vec3& s) { return propagatePose(s, ds, dth); };
  auto h = [&](const Vec3& s) { return predictRangeBearing(s, xm, ym); };
  Innovation<3, 2> in;
  for (auto _ : state) {
    ukf.reset(x0, P0);
    benchmark::DoNotOptimize(ukf.predict(f, Q));
    if (ukf.innovate<2>(h, R, z, 1u << 1, in) && in.mahalanobis <= 9.21) ukf.correct(in);
    benchmark::DoNotOptimize(ukf.x().data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_UkfPredictUpdate);

void BM_ModelCallsOnly(benchmark::State& state) {
  Vec3 x(0.0, 0.0, 1.5707963267948966);
  const double ds = 0.015, dth = headingIncrement(ds, 0.05, kWheelbase);
  for (auto _ : state) {
    for (int k = 0; k < 7; ++k) {
      const Vec3 s = x + Vec3(1e-3 * k, -1e-3 * k, 1e-2 * k);
      benchmark::DoNotOptimize(propagatePose(s, ds, dth));
      benchmark::DoNotOptimize(predictRangeBearing(s, 0.05, 1.5));
    }
  }
}
BENCHMARK(BM_ModelCallsOnly);

void BM_FilterPredictUpdate(benchmark::State& state) {
  FilterConfig cfg;
  cfg.type = "ukf_gated";
  MarkerMap map;
  for (int i = 0; i < 20; ++i) map.push_back(Marker{i, 0.0, 2.0 * (i + 1)});
  auto filter = makeFilter(cfg, map);
  const FilterState start = filter->state();
  OdometryInput odo;
  odo.delta_s = 0.5;
  odo.has_steering = true;
  odo.steering = 0.0;
  RulerDetection det;
  det.lateral_offset = 0.01;
  for (auto _ : state) {
    state.PauseTiming();
    filter->initialize(start);
    state.ResumeTiming();
    filter->predict(odo);
    GateDecision d = filter->update(det);
    benchmark::DoNotOptimize(d.accepted);
  }
}
BENCHMARK(BM_FilterPredictUpdate);

}  // namespace

BENCHMARK_MAIN();
