// MapIndex against brute force: the same markers for every query (randomized maps with markers
// on cell borders, shared positions and non-finite ones), the same closest pair, the same id
// lookup.
#include <gtest/gtest.h>

#include <cmath>
#include <array>
#include <limits>
#include <algorithm>
#include <random>
#include <vector>

#include "lcmloc/core/map_index.hpp"

using namespace lcmloc::core;

namespace {

std::vector<uint32_t> bruteNear(const MarkerMap& map, double x, double y, double r) {
  std::vector<uint32_t> out;
  const double lx = x - r, hx = x + r, ly = y - r, hy = y + r;
  for (std::size_t i = 0; i < map.size(); ++i) {
    const Marker& m = map[i];
    const bool odd = !std::isfinite(m.x) || !std::isfinite(m.y);
    if (odd || (lx <= m.x && m.x <= hx && ly <= m.y && m.y <= hy)) out.push_back(static_cast<uint32_t>(i));
  }
  return out;
}

double bruteClosest(const MarkerMap& map) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < map.size(); ++i)
    for (std::size_t j = i + 1; j < map.size(); ++j) {
      const Marker &a = map[i], &b = map[j];
      if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y)) continue;
      best = std::min(best, std::hypot(b.x - a.x, b.y - a.y));
    }
  return best;
}

/// A random map of one of several shapes: a cloud, a road along y (every x the same), a diagonal
/// road, a grid of integer positions (markers on every cell border of a cell size that is a
/// power of two), with copies of positions and a few non-finite markers.
MarkerMap randomMap(std::mt19937_64& rng, int shape, int n) {
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::uniform_int_distribution<int> k(-20, 20);
  MarkerMap map;
  for (int i = 0; i < n; ++i) {
    Marker m;
    m.id = i;
    switch (shape) {
      case 0: m.x = u(rng), m.y = u(rng); break;
      case 1: m.x = 3.0, m.y = 2.0 * i; break;
      case 2: m.x = 0.5 * i, m.y = 0.5 * i + 1e-3 * k(rng); break;
      default: m.x = 0.25 * k(rng), m.y = 0.5 * k(rng); break;
    }
    map.push_back(m);
  }
  std::uniform_int_distribution<int> pick(0, n - 1);
  for (int i = 0; i < n / 10; ++i) {  // shared positions (new ids)
    Marker m = map[static_cast<std::size_t>(pick(rng))];
    m.id = n + i;
    map.push_back(m);
  }
  if (shape == 0) {
    map.push_back({-1, std::numeric_limits<double>::quiet_NaN(), 1.0});
    map.push_back({-2, 1.0, std::numeric_limits<double>::infinity()});
  }
  std::shuffle(map.begin(), map.end(), rng);
  return map;
}

}  // namespace

TEST(MapIndex, NearIsExactlyTheBruteForceBoxForRandomMapsAndQueries) {
  std::mt19937_64 rng(36);
  std::vector<uint32_t> got;
  int nonempty = 0;
  for (int trial = 0; trial < 80; ++trial) {
    const int shape = trial % 4;
    const MarkerMap map = randomMap(rng, shape, 1 + static_cast<int>(rng() % 400));
    const MapIndex index(map);
    ASSERT_GT(index.cellSize(), 0.0);
    std::uniform_real_distribution<double> q(-80.0, 260.0), rad(0.0, 30.0);
    for (int i = 0; i < 200; ++i) {
      double x = q(rng), y = q(rng), r = rad(rng);
      if (i % 3 == 0) {  // centred on a marker, the box's edge on other markers and cell borders
        const Marker& m = map[rng() % map.size()];
        if (std::isfinite(m.x) && std::isfinite(m.y)) x = m.x, y = m.y;
        r = 0.25 * static_cast<double>(rng() % 9);
      }
      index.near(x, y, r, got);
      const auto want = bruteNear(map, x, y, r);
      ASSERT_EQ(got, want) << "shape " << shape << " query (" << x << ", " << y << ") r " << r;
      nonempty += want.size() > 2 ? 1 : 0;
    }
  }
  EXPECT_GT(nonempty, 1000);  // the queries did find markers
}

TEST(MapIndex, TwoDenseClustersFarApartAreIndexedAsExactly) {
  // a fine cell over a wide extent: too many cells to pack a cell and an index in 64 bits
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  MarkerMap map;
  for (int i = 0; i < 70000; ++i) {
    const double o = i % 2 ? 1e6 : 0.0;
    map.push_back({i, o + u(rng), o + u(rng)});
  }
  const MapIndex index(map);
  EXPECT_LT(index.cellSize(), 0.1);
  std::vector<uint32_t> got;
  for (int i = 0; i < 40; ++i) {
    const Marker& m = map[rng() % map.size()];
    const double r = 0.05 * (i % 5);
    index.near(m.x, m.y, r, got);
    ASSERT_EQ(got, bruteNear(map, m.x, m.y, r)) << i;
  }
}

TEST(MapIndex, AQueryThatIsNotFiniteGivesEveryMarker) {
  const MarkerMap map{{1, 0, 0}, {2, 5, 5}, {3, -5, 2}};
  const MapIndex index(map);
  std::vector<uint32_t> got;
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const auto& q : {std::array<double, 3>{nan, 0, 1}, {0, inf, 1}, {0, 0, nan}, {0, 0, inf}, {0, 0, -1}}) {
    index.near(q[0], q[1], q[2], got);
    EXPECT_EQ(got, (std::vector<uint32_t>{0, 1, 2}));
  }
  index.near(100, 100, 1, got);
  EXPECT_TRUE(got.empty());
  MapIndex empty{MarkerMap{}};
  empty.near(0, 0, 1, got);
  EXPECT_TRUE(got.empty());
  EXPECT_EQ(empty.closestPair(), inf);
}

TEST(MapIndex, ClosestPairIsTheBruteForceOne) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const MarkerMap map = randomMap(rng, trial % 4, 1 + static_cast<int>(rng() % 300));
    EXPECT_EQ(MapIndex(map).closestPair(), bruteClosest(map)) << "trial " << trial;
  }
  // no shared positions, widely spaced and uneven: the cells have to grow to find the pair
  MarkerMap sparse;
  for (int i = 0; i < 200; ++i) sparse.push_back({i, 1000.0 * i + 0.001 * i * i, 7.0 * (i % 3)});
  sparse.push_back({999, 1e6, 1e6});
  EXPECT_EQ(MapIndex(sparse).closestPair(), bruteClosest(sparse));
  // a road along y, every x the same: the case sorting by x made quadratic
  MarkerMap road;
  for (int i = 0; i < 20000; ++i) road.push_back({i, 5.0, 1.5 * i + (i == 777 ? 0.25 : 0.0)});
  EXPECT_EQ(MapIndex(road).closestPair(), 1.25);
  EXPECT_EQ(MapIndex(MarkerMap{{1, 2, 3}}).closestPair(), std::numeric_limits<double>::infinity());
}

TEST(MapIndex, FindGivesTheFirstMarkerOfAnId) {
  const MarkerMap map{{7, 1, 1}, {-3, 2, 2}, {7, 3, 3}, {0, 4, 4}, {2000000000, 5, 5}};
  const MapIndex index(map);
  ASSERT_NE(index.find(7), nullptr);
  EXPECT_EQ(index.find(7), &index.markers()[0]);
  EXPECT_EQ(index.find(-3)->x, 2);
  EXPECT_EQ(index.find(2000000000)->x, 5);
  EXPECT_EQ(index.find(0)->x, 4);
  EXPECT_EQ(index.find(1), nullptr);
  EXPECT_EQ(index.find(-7), nullptr);
}
