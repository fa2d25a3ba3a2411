// Maps at road scale: loading a map file and association per detection, by the size of the map.
//   BM_MapLoad/N:        app::csv::loadMap of an N-marker file (a magnetic road along y, the
//                        worst case of an index sorted by x) and a FusionEngine over it with the
//                        ruler filter active and three shadows (ukf, ukf_calib, ukf_landmarks).
//                        Counters: rss_MB, the resident memory the loaded engine holds (VmRSS after
//                        minus before), and peak_MB, the peak during the load (VmHWM).
//   BM_RulerDetection/N: one odometry step and one ruler detection through "ukf_gated" driving
//                        along that road: the association looks up the markers near the pose.
//   BM_LandmarkDetection/N: one odometry step and one range-bearing observation of an unknown
//                        landmark (nearest neighbour) through "ukf_landmarks" in a square field.
//   BM_IndexNear/N, BM_KdTreeNear/N (with nanoflann): the candidates of one ruler association
//                        (box / radius 2.5 m, at one marker after the other along the road) from
//                        the grid of MapIndex and from a k-d tree, both in map order.
//   BM_IndexBuild/N, BM_KdTreeBuild/N: building them.
// Run: build/test-bin/bench_map --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "lcmloc/app/csv.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/map_index.hpp"

#ifdef LCMLOC_BENCH_NANOFLANN
#include <nanoflann.hpp>
#endif

namespace {

using namespace lcmloc;
using core::Marker;
using core::MarkerMap;

constexpr double kSpacing = 2.0;  ///< [m] between markers along the road
constexpr double kL1 = 1.5;       ///< [m] the ruler ahead of M

/// n markers along y at x = 0 (a road), kSpacing apart, with a small lateral zigzag.
MarkerMap road(int64_t n) {
  MarkerMap m;
  m.reserve(static_cast<std::size_t>(n));
  for (int64_t i = 0; i < n; ++i) m.push_back({static_cast<int>(i), 0.01 * static_cast<double>(i % 3), kSpacing * static_cast<double>(i)});
  return m;
}

/// n landmarks on a square lattice 10 m apart.
MarkerMap field(int64_t n) {
  const auto side = static_cast<int64_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  MarkerMap m;
  for (int64_t i = 0; i < n; ++i) m.push_back({static_cast<int>(i), 10.0 * static_cast<double>(i % side), 10.0 * static_cast<double>(i / side)});
  return m;
}

/// [MB] a field of /proc/self/status (VmRSS, VmHWM).
double statusMb(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string k;
  double kb = 0;
  while (in >> k) {
    if (k == std::string(key) + ":") {
      in >> kb;
      return kb / 1024.0;
    }
    in.ignore(1 << 12, '\n');
  }
  return 0.0;
}

/// Starts the peak resident size (VmHWM) afresh (Linux: clear_refs 5).
void resetPeak() { std::ofstream("/proc/self/clear_refs") << "5"; }

/// Freed blocks go back to the system, so that every run starts from the same resident size.
void releaseFreed() {
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  malloc_trim(0);
}

void BM_MapLoad(benchmark::State& state) {
  const int64_t n = state.range(0);
  const std::string file = (std::filesystem::temp_directory_path() / ("lcmloc_bench_map_" + std::to_string(n) + ".csv")).string();
  app::csv::writeMap(file, road(n));
  core::EngineConfig cfg;
  cfg.filter.type = "ukf_gated";
  cfg.shadow = {"ukf", "ukf_calib", "ukf_landmarks"};
  double rss = 0, peak = 0;
  for (auto _ : state) {
    state.PauseTiming();
    releaseFreed();
    resetPeak();
    const double before = statusMb("VmRSS");
    state.ResumeTiming();
    {
      core::FusionEngine engine(cfg, app::csv::loadMap(file), core::EngineOutputs{});
      benchmark::DoNotOptimize(engine.activeFilter());
      state.PauseTiming();
      rss = statusMb("VmRSS") - before;
      peak = statusMb("VmHWM") - before;
    }
    state.ResumeTiming();
  }
  state.counters["rss_MB"] = rss;
  state.counters["peak_MB"] = peak;
  std::remove(file.c_str());
}
BENCHMARK(BM_MapLoad)->Arg(0)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_RulerDetection(benchmark::State& state) {
  const int64_t n = state.range(0);
  core::FilterConfig c;
  c.type = "ukf_gated";
  c.ruler_offset = kL1;
  const auto filter = core::makeFilter(c, road(n));
  core::FilterState start = filter->state();
  // M a marker spacing before a marker, heading +y, so that the ruler passes over it after one
  // step of one spacing; the ruler's lateral offset is then the marker's -x (left of +y is -x).
  auto restart = [&](int64_t marker) {
    start.x.head<3>() << 0.0, kSpacing * static_cast<double>(marker) - kL1 - kSpacing, M_PI / 2;
    start.P.topLeftCorner<3, 3>() = core::Vec3(1e-4, 1e-4, 1e-5).asDiagonal();
    filter->initialize(start);
  };
  const int64_t first = n / 2, last = n - 2;
  int64_t marker = first;
  restart(marker);
  core::OdometryInput odo;
  odo.delta_s = kSpacing;
  odo.has_steering = true;
  core::RulerDetection det;
  int64_t accepted = 0;
  for (auto _ : state) {
    odo.utime += 100'000;
    filter->predict(odo);
    det.utime = odo.utime;
    det.lateral_offset = -0.01 * static_cast<double>(marker % 3);
    det.quality = 1.0;
    const core::GateDecision d = filter->update(det);
    accepted += d.accepted ? 1 : 0;
    if (++marker > last) restart(marker = first);
  }
  state.counters["accepted"] = benchmark::Counter(static_cast<double>(accepted), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_RulerDetection)->Arg(1'000)->Arg(1'000'000);

void BM_LandmarkDetection(benchmark::State& state) {
  const int64_t n = state.range(0);
  core::FilterConfig c;
  c.type = "ukf_landmarks";
  const auto filter = core::makeFilter(c, field(n));
  core::FilterState s = filter->state();
  const double mid = 10.0 * std::floor(std::sqrt(static_cast<double>(n)) / 2.0);  // a landmark amid the field
  s.x.head<3>() << mid - 5.0, mid - 5.0, 0.0;
  s.P.topLeftCorner<3, 3>() = core::Vec3(0.25, 0.25, 1e-3).asDiagonal();
  core::LandmarkObservation obs;
  obs.range = std::hypot(5.0, 5.0);  // that landmark from 5 m before it in x and y
  obs.bearing = M_PI / 4;
  int64_t accepted = 0;
  for (auto _ : state) {
    filter->initialize(s);
    ++obs.utime;
    const auto d = filter->update(obs);
    accepted += d && d->accepted ? 1 : 0;
  }
  state.counters["accepted"] = benchmark::Counter(static_cast<double>(accepted), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_LandmarkDetection)->Arg(1'000)->Arg(1'000'000);

void BM_IndexBuild(benchmark::State& state) {
  const MarkerMap map = road(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(core::MapIndex(map).cellSize());
}
BENCHMARK(BM_IndexBuild)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

void BM_IndexNear(benchmark::State& state) {
  const int64_t n = state.range(0);
  const core::MapIndex index(road(n));
  std::vector<uint32_t> out;
  int64_t i = 0, found = 0;
  for (auto _ : state) {
    index.near(0.0, kSpacing * static_cast<double>(i) + 0.3, 2.5, out);
    found += static_cast<int64_t>(out.size());
    i = (i + 1) % n;  // along the road, as a vehicle queries
  }
  state.counters["found"] = benchmark::Counter(static_cast<double>(found), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_IndexNear)->Arg(1'000)->Arg(1'000'000);

#ifdef LCMLOC_BENCH_NANOFLANN
struct Cloud {
  const MarkerMap* m;
  std::size_t kdtree_get_point_count() const { return m->size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const { return dim == 0 ? (*m)[i].x : (*m)[i].y; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const { return false; }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 2, uint32_t>;

void BM_KdTreeBuild(benchmark::State& state) {
  const MarkerMap map = road(state.range(0));
  const Cloud cloud{&map};
  for (auto _ : state) {
    KdTree tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    benchmark::DoNotOptimize(&tree);
  }
}
BENCHMARK(BM_KdTreeBuild)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

/// The same candidates as BM_IndexNear wants: within 2.5 m, in map order (the association's
/// tie-break), so the results are sorted by index as the grid's are.
void BM_KdTreeNear(benchmark::State& state) {
  const int64_t n = state.range(0);
  const MarkerMap map = road(n);
  const Cloud cloud{&map};
  KdTree tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  std::vector<std::pair<uint32_t, double>> hits;
  std::vector<uint32_t> out;
  nanoflann::SearchParams params;
  params.sorted = false;
  int64_t i = 0, found = 0;
  for (auto _ : state) {
    const double q[2] = {0.0, kSpacing * static_cast<double>(i) + 0.3};
    tree.radiusSearch(q, 2.5 * 2.5, hits, params);
    out.clear();
    for (const auto& h : hits) out.push_back(h.first);
    std::sort(out.begin(), out.end());
    found += static_cast<int64_t>(out.size());
    i = (i + 1) % n;  // along the road, as a vehicle queries
  }
  state.counters["found"] = benchmark::Counter(static_cast<double>(found), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_KdTreeNear)->Arg(1'000)->Arg(1'000'000);
#endif

}  // namespace

BENCHMARK_MAIN();
