#pragma once
// The map of the filters (magnetic markers, landmarks, beacons) with a spatial index: a uniform
// grid over the markers' positions, and a lookup by id. Built once per map in O(n log n) and
// shared by every filter the engine runs, so that a filter's association looks at the markers
// near its predicted pose only, whatever the size of the map.
#include <cstdint>
#include <memory>
#include <vector>

#include "lcmloc/core/types.hpp"

namespace lcmloc::core {

class MapIndex {
 public:
  /// Indexes markers (kept in their order). Time O(n log n); memory about 8 to 16 bytes per
  /// marker besides the markers themselves.
  explicit MapIndex(MarkerMap markers);

  const MarkerMap& markers() const { return markers_; }
  std::size_t size() const { return markers_.size(); }
  const Marker& operator[](std::size_t i) const { return markers_[i]; }

  /// The first marker (in map order) with this id; nullptr: none. O(log n).
  const Marker* find(int id) const;

  /// Replaces out by the indices into markers(), ascending (map order), of every marker with
  /// x - r <= m.x <= x + r and y - r <= m.y <= y + r (the square box of half-width r, its bounds
  /// computed as doubles, border included), and of every marker whose position is not finite.
  /// A query that is not finite (x, y or r not finite, or r < 0) gives every marker: the caller's
  /// own test decides. O(log n + markers in the cells the box touches).
  void near(double x, double y, double r, std::vector<uint32_t>& out) const;

  /// [m] The smallest distance between two markers with finite positions (std::hypot of their
  /// differences; 0 for two at one position); +inf with fewer than two. O(n log n), computed
  /// once and kept.
  double closestPair() const { return closest_; }

  /// [m] The grid's cell: the size at which the occupied cells hold about two markers each.
  double cellSize() const { return grid_.cell; }

  /// A box half-width that contains every point within distance r of (x, y) as a caller
  /// computes it from differences m - (x, y) (r widened by far more than rounding can move it).
  static double widen(double r, double x, double y);

 private:
  /// Markers sorted into cells of one size: cell (ix, iy) has key iy << 32 | ix; keys ascending,
  /// the markers of keys[k] are order[start[k] .. start[k + 1]), in map order.
  struct Grid {
    double x0 = 0.0, y0 = 0.0, cell = 1.0;
    int64_t nx = 0, ny = 0;
    std::vector<uint64_t> keys;
    std::vector<uint32_t> start;
    std::vector<uint32_t> order;
    int64_t cellX(double x) const;
    int64_t cellY(double y) const;
    static uint64_t key(int64_t ix, int64_t iy) { return static_cast<uint64_t>(iy) << 32 | static_cast<uint64_t>(ix); }
  };
  Grid build(double cell) const;
  double chooseCell() const;
  double closestWithin(const Grid& g, int64_t reach) const;
  double computeClosestPair() const;

  MarkerMap markers_;
  std::size_t finite_ = 0;         ///< markers with a finite position
  std::vector<uint32_t> odd_;     ///< markers whose position is not finite (always returned)
  std::vector<uint32_t> by_id_;   ///< indices sorted by (id, index)
  double xmin_ = 0.0, ymin_ = 0.0, xmax_ = 0.0, ymax_ = 0.0;
  Grid grid_;
  double closest_ = 0.0;
};

using SharedMapIndex = std::shared_ptr<const MapIndex>;

}  // namespace lcmloc::core
