#include "lcmloc/core/map_index.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

namespace lcmloc::core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// The finest resolution the cell size is chosen at: 2^kLevels steps across the map's extent.
constexpr int kLevels = 24;
/// Markers per occupied cell that the cell size aims at.
constexpr double kOccupancy = 2.0;

bool finitePosition(const Marker& m) { return std::isfinite(m.x) && std::isfinite(m.y); }

/// x's bits at the even bit positions, y's at the odd ones (Z order).
uint64_t interleave(uint64_t x, uint64_t y) {
  auto spread = [](uint64_t v) {
    v &= 0xFFFFFFFFull;
    v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
    v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
    v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
    v = (v | (v << 2)) & 0x3333333333333333ull;
    v = (v | (v << 1)) & 0x5555555555555555ull;
    return v;
  };
  return spread(x) | spread(y) << 1;
}

}  // namespace

MapIndex::MapIndex(MarkerMap markers) : markers_(std::move(markers)) {
  const std::size_t n = markers_.size();
  // by id: (id, index) packed in one integer each, so that the sort is a plain integer sort
  std::vector<uint64_t> ids(n);
  for (std::size_t i = 0; i < n; ++i)
    ids[i] = static_cast<uint64_t>(static_cast<uint32_t>(markers_[i].id) ^ 0x80000000u) << 32 | i;
  std::sort(ids.begin(), ids.end());
  by_id_.resize(n);
  for (std::size_t i = 0; i < n; ++i) by_id_[i] = static_cast<uint32_t>(ids[i]);
  ids = {};

  xmin_ = ymin_ = kInf;
  xmax_ = ymax_ = -kInf;
  for (std::size_t i = 0; i < n; ++i) {
    const Marker& m = markers_[i];
    if (!finitePosition(m)) {
      odd_.push_back(static_cast<uint32_t>(i));
      continue;
    }
    ++finite_;
    xmin_ = std::min(xmin_, m.x);
    xmax_ = std::max(xmax_, m.x);
    ymin_ = std::min(ymin_, m.y);
    ymax_ = std::max(ymax_, m.y);
  }
  if (finite_ == 0) xmin_ = ymin_ = xmax_ = ymax_ = 0.0;
  grid_ = build(chooseCell());
  closest_ = computeClosestPair();
}

double MapIndex::widen(double r, double x, double y) {
  return r * (1.0 + 1e-9) + (std::abs(x) + std::abs(y)) * 1e-12 + 1e-12;
}

const Marker* MapIndex::find(int id) const {
  const auto it = std::lower_bound(by_id_.begin(), by_id_.end(), id,
                                   [this](uint32_t i, int v) { return markers_[i].id < v; });
  if (it == by_id_.end() || markers_[*it].id != id) return nullptr;
  return &markers_[*it];
}

namespace {
/// floor(v / cell) within [0, n - 1] (NaN: 0): monotone in v.
int64_t cellOf(double v, double cell, int64_t n) {
  const double c = std::floor(v / cell);
  if (!(c > 0.0)) return 0;
  return c >= static_cast<double>(n - 1) ? n - 1 : static_cast<int64_t>(c);
}
/// Cells across an extent: 1 when the extent or the cell is not finite.
int64_t cellsAcross(double extent, double cell) {
  const double f = std::floor(extent / cell);
  return f >= 0.0 && f < 2147483647.0 ? static_cast<int64_t>(f) + 1 : 1;
}
}  // namespace

int64_t MapIndex::Grid::cellX(double x) const { return cellOf(x - x0, cell, nx); }
int64_t MapIndex::Grid::cellY(double y) const { return cellOf(y - y0, cell, ny); }

/// The cell size at which the occupied cells hold about kOccupancy markers each (or, when many
/// markers share positions, twice as many as they hold at the finest resolution): the finite
/// markers are sorted in Z order at the finest resolution once; the cells of every coarser level
/// are then runs of one prefix, counted in one pass.
double MapIndex::chooseCell() const {
  const double extent = std::max(xmax_ - xmin_, ymax_ - ymin_);
  if (!std::isfinite(extent)) return kInf;  // (coordinates near the largest double: one cell)
  if (finite_ < 2 || !(extent > 0.0)) return 1.0;
  const double q = extent / static_cast<double>(1 << kLevels);
  const double top = static_cast<double>((1 << kLevels) - 1);
  std::vector<uint64_t> codes;
  codes.reserve(finite_);
  for (const Marker& m : markers_) {
    if (!finitePosition(m)) continue;
    const auto qx = static_cast<uint64_t>(std::min(std::floor((m.x - xmin_) / q), top));
    const auto qy = static_cast<uint64_t>(std::min(std::floor((m.y - ymin_) / q), top));
    codes.push_back(interleave(qx, qy));
  }
  std::sort(codes.begin(), codes.end());
  // two neighbours in Z order are in different cells of level k (2^k fine steps) iff they
  // differ above bit 2k: at every level up to (highest differing bit) / 2
  std::vector<std::size_t> last_level(kLevels + 1, 0);
  for (std::size_t i = 1; i < codes.size(); ++i) {
    const uint64_t d = codes[i] ^ codes[i - 1];
    if (d == 0) continue;
    const int msb = 63 - __builtin_clzll(d);
    ++last_level[std::min(msb / 2, kLevels)];
  }
  std::vector<std::size_t> cells(kLevels + 1, 1);
  std::size_t above = 0;
  for (int k = kLevels; k >= 0; --k) {
    above += last_level[k];
    cells[k] = 1 + above;
  }
  const double n = static_cast<double>(codes.size());
  const double target = std::max(kOccupancy, 2.0 * n / static_cast<double>(cells[0]));
  int level = 0;
  for (int k = 0; k <= kLevels; ++k)
    if (n / static_cast<double>(cells[k]) <= target) level = k;
  return q * static_cast<double>(uint64_t{1} << level);
}

/// The markers sorted by (cell, index). When the cell number (row-major) and the index fit in
/// 64 bits together, as they do for maps of millions of markers, each marker is one packed
/// integer (8 bytes while sorting); otherwise a (key, index) pair.
MapIndex::Grid MapIndex::build(double cell) const {
  Grid g;
  g.x0 = xmin_;
  g.y0 = ymin_;
  g.cell = cell;
  g.nx = cellsAcross(xmax_ - xmin_, cell);
  g.ny = cellsAcross(ymax_ - ymin_, cell);
  auto bits = [](uint64_t v) { return v == 0 ? 0 : 64 - __builtin_clzll(v); };
  const int index_bits = bits(markers_.size());
  const int cell_bits = bits(static_cast<uint64_t>(g.nx) * static_cast<uint64_t>(g.ny));
  if (index_bits + cell_bits <= 64) {
    std::vector<uint64_t> packed;
    packed.reserve(finite_);
    for (std::size_t i = 0; i < markers_.size(); ++i)
      if (finitePosition(markers_[i])) {
        const auto c = static_cast<uint64_t>(g.cellY(markers_[i].y) * g.nx + g.cellX(markers_[i].x));
        packed.push_back(c << index_bits | i);
      }
    std::sort(packed.begin(), packed.end());
    const uint64_t mask = (uint64_t{1} << index_bits) - 1;
    g.order.resize(packed.size());
    std::size_t cells = 0;
    for (std::size_t k = 0; k < packed.size(); ++k) {
      g.order[k] = static_cast<uint32_t>(packed[k] & mask);
      cells += k == 0 || (packed[k] >> index_bits) != (packed[k - 1] >> index_bits) ? 1 : 0;
    }
    g.keys.reserve(cells);
    g.start.reserve(cells + 1);
    for (std::size_t k = 0; k < packed.size(); ++k) {
      const uint64_t c = packed[k] >> index_bits;
      if (k == 0 || c != packed[k - 1] >> index_bits) {
        g.keys.push_back(Grid::key(static_cast<int64_t>(c % static_cast<uint64_t>(g.nx)), static_cast<int64_t>(c / static_cast<uint64_t>(g.nx))));
        g.start.push_back(static_cast<uint32_t>(k));
      }
    }
    g.start.push_back(static_cast<uint32_t>(packed.size()));
    return g;
  }
  std::vector<std::pair<uint64_t, uint32_t>> keyed;
  keyed.reserve(finite_);
  for (std::size_t i = 0; i < markers_.size(); ++i)
    if (finitePosition(markers_[i]))
      keyed.emplace_back(Grid::key(g.cellX(markers_[i].x), g.cellY(markers_[i].y)), static_cast<uint32_t>(i));
  std::sort(keyed.begin(), keyed.end());
  g.order.reserve(keyed.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) {
    if (k == 0 || keyed[k].first != keyed[k - 1].first) {
      g.keys.push_back(keyed[k].first);
      g.start.push_back(static_cast<uint32_t>(k));
    }
    g.order.push_back(keyed[k].second);
  }
  g.start.push_back(static_cast<uint32_t>(keyed.size()));
  return g;
}

void MapIndex::near(double x, double y, double r, std::vector<uint32_t>& out) const {
  out.clear();
  if (markers_.empty()) return;
  if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(r) && r >= 0.0)) {
    out.resize(markers_.size());
    std::iota(out.begin(), out.end(), 0u);
    return;
  }
  const double lx = x - r, hx = x + r, ly = y - r, hy = y + r;
  auto inBox = [&](const Marker& m) { return lx <= m.x && m.x <= hx && ly <= m.y && m.y <= hy; };
  const Grid& g = grid_;
  if (!g.keys.empty() && !(hx < xmin_ || lx > xmax_ || hy < ymin_ || ly > ymax_)) {
    const int64_t ix0 = g.cellX(lx), ix1 = g.cellX(hx), iy0 = g.cellY(ly), iy1 = g.cellY(hy);
    if (static_cast<uint64_t>(iy1 - iy0 + 1) > g.keys.size()) {
      for (std::size_t i = 0; i < markers_.size(); ++i)  // more rows than cells: one pass is less work
        if (inBox(markers_[i])) out.push_back(static_cast<uint32_t>(i));
    } else {
      for (int64_t iy = iy0; iy <= iy1; ++iy) {
        const uint64_t last = Grid::key(ix1, iy);
        for (auto k = static_cast<std::size_t>(std::lower_bound(g.keys.begin(), g.keys.end(), Grid::key(ix0, iy)) - g.keys.begin());
             k < g.keys.size() && g.keys[k] <= last; ++k)
          for (uint32_t j = g.start[k]; j < g.start[k + 1]; ++j)
            if (inBox(markers_[g.order[j]])) out.push_back(g.order[j]);
      }
    }
  }
  out.insert(out.end(), odd_.begin(), odd_.end());
  std::sort(out.begin(), out.end());
}

/// The smallest distance between two markers whose cells of g are at most `reach` cells apart
/// in x and in y.
double MapIndex::closestWithin(const Grid& g, int64_t reach) const {
  double best = kInf;
  auto closer = [&](uint32_t a, uint32_t b) {
    const Marker &p = markers_[a], &q = markers_[b];
    best = std::min(best, std::hypot(q.x - p.x, q.y - p.y));
  };
  for (std::size_t k = 0; k < g.keys.size(); ++k) {
    const int64_t ix = static_cast<int64_t>(g.keys[k] & 0xFFFFFFFFu), iy = static_cast<int64_t>(g.keys[k] >> 32);
    for (uint32_t a = g.start[k]; a < g.start[k + 1]; ++a)
      for (uint32_t b = a + 1; b < g.start[k + 1]; ++b) closer(g.order[a], g.order[b]);
    // each pair of cells once: the next ones in this row, and those of the rows above
    for (int64_t dy = 0; dy <= reach && iy + dy < g.ny; ++dy) {
      const int64_t from = dy == 0 ? ix + 1 : std::max<int64_t>(ix - reach, 0);
      const int64_t to = std::min(ix + reach, g.nx - 1);
      if (from > to) continue;
      const uint64_t last = Grid::key(to, iy + dy);
      for (auto j = static_cast<std::size_t>(std::lower_bound(g.keys.begin(), g.keys.end(), Grid::key(from, iy + dy)) - g.keys.begin());
           j < g.keys.size() && g.keys[j] <= last; ++j)
        for (uint32_t a = g.start[k]; a < g.start[k + 1]; ++a)
          for (uint32_t b = g.start[j]; b < g.start[j + 1]; ++b) closer(g.order[a], g.order[b]);
    }
  }
  return best;
}

/// A pair closer than (reach - 1/2) cells is at most `reach` cells apart (rounding included):
/// once the closest pair found that far is that close, it is the closest of all. The index's own
/// grid is searched two cells around each cell; when that finds no pair close enough, grids of
/// doubling cells one cell around, until one does or the whole map lies in adjacent cells.
double MapIndex::computeClosestPair() const {
  if (finite_ < 2) return kInf;
  double best = closestWithin(grid_, 2);
  if (best <= 1.5 * grid_.cell || (grid_.nx <= 3 && grid_.ny <= 3)) return best;
  for (double cell = 2.0 * grid_.cell;; cell *= 2.0) {
    const Grid g = build(cell);
    best = closestWithin(g, 1);
    if (best <= 0.5 * cell || (g.nx <= 2 && g.ny <= 2)) return best;
  }
}

}  // namespace lcmloc::core
