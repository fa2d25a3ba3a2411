#include "lcmloc/sim/scenario_config.hpp"

#include <algorithm>
#include <cmath>

namespace lcmloc::sim {
namespace {

uint64_t fnv1a64(const std::string& s) {
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

}  // namespace

uint64_t componentSeed(uint64_t master, const std::string& component) {
  return splitmix64(master ^ fnv1a64(component));
}

MarkerLayout respaced(const MarkerLayout& layout, double spacing) {
  MarkerLayout out = layout;
  const double span = std::max(layout.count - 1, 0) * layout.spacing;
  out.count = layout.count > 0 ? static_cast<int>(std::floor(span / spacing + 1e-9)) + 1 : 0;
  out.spacing = spacing;
  return out;
}

double stopArcLength(const ScenarioConfig& sc, double path_length) {
  if (sc.markers.count <= 0) return path_length;
  return sc.markers.first_at + (sc.markers.count - 1) * sc.markers.spacing + sc.vehicle.end_margin;
}

}  // namespace lcmloc::sim
