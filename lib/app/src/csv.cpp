#include "lcmloc/app/csv.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "lcmloc/app/files.hpp"

namespace lcmloc::app::csv {

std::vector<std::string> split(const std::string& line) {
  std::string s = line;
  if (!s.empty() && s.back() == '\r') s.pop_back();
  std::vector<std::string> out;
  if (s.empty()) return out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = s.find(',', start);
    std::string f = s.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto b = f.find_first_not_of(" \t");
    const auto e = f.find_last_not_of(" \t");
    out.push_back(b == std::string::npos ? std::string() : f.substr(b, e - b + 1));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

bool parseNumber(const std::string& f, std::size_t column, double& out, std::string& why) {
  if (f.empty()) {
    why = fmt::format("column {}: empty", column);
    return false;
  }
  const char* b = f.c_str();
  char* e = nullptr;
  errno = 0;
  const double v = std::strtod(b, &e);
  // strtod also reads C hexadecimal ("0x10" = 16): no CSV writer means that, so it is refused
  if (e == b || *e != '\0' || errno == ERANGE || f.find_first_of("xX") != std::string::npos) {
    why = fmt::format("column {}: not a number: '{}'", column, f);
    return false;
  }
  if (!std::isfinite(v)) {
    why = fmt::format("column {}: not finite: '{}'", column, f);
    return false;
  }
  out = v;
  return true;
}

bool parseRow(const std::string& line, std::size_t n, std::vector<double>& out, std::string& why) {
  out.clear();
  const auto fields = split(line);
  if (fields.size() != n) {
    why = fmt::format("expected {} columns, got {}", n, fields.size());
    return false;
  }
  for (std::size_t i = 0; i < fields.size(); ++i) {
    double v = 0;
    if (!parseNumber(fields[i], i + 1, v, why)) return false;
    out.push_back(v);
  }
  return true;
}

std::ifstream openCsv(const std::string& path, std::string& header) {
  if (const std::string problem = fileProblem(path); !problem.empty())
    throw std::runtime_error("'" + path + "': " + (problem == kNoSuchFile ? "cannot open (does it exist?)" : problem));
  std::ifstream in(path);
  if (!in) throw std::runtime_error("'" + path + "': cannot open: " + std::strerror(errno));
  header.clear();
  std::getline(in, header);
  if (header.rfind("\xEF\xBB\xBF", 0) == 0) header.erase(0, 3);  // UTF-8 byte-order mark
  if (!header.empty() && header.back() == '\r') header.pop_back();
  return in;
}

std::ifstream openWithHeader(const std::string& path, const std::string& header) {
  std::string h;
  auto in = openCsv(path, h);
  if (h != header)
    throw std::runtime_error(fmt::format("'{}': line 1: expected the header '{}', got '{}'", path, header, h));
  return in;
}

namespace {

/// The first repeated id in file order: the line of its second row and of its first.
struct Duplicate {
  int64_t again = 0, first = 0;  ///< 0: none
  int id = 0;
};
/// Sorting (id, row) pairs: O(n log n) and 8 bytes a marker (ids >= 0).
Duplicate firstDuplicate(const core::MarkerMap& map, const std::vector<uint32_t>& lines) {
  std::vector<uint64_t> keyed(map.size());
  for (std::size_t i = 0; i < map.size(); ++i) keyed[i] = static_cast<uint64_t>(map[i].id) << 32 | i;
  std::sort(keyed.begin(), keyed.end());
  Duplicate found;
  for (std::size_t k = 1; k < keyed.size(); ++k) {
    if ((keyed[k] >> 32) != (keyed[k - 1] >> 32) || (k >= 2 && (keyed[k] >> 32) == (keyed[k - 2] >> 32))) continue;
    const int64_t again = lines[keyed[k] & 0xFFFFFFFFu];  // the id's second row
    if (found.again == 0 || again < found.again)
      found = {again, lines[keyed[k - 1] & 0xFFFFFFFFu], static_cast<int>(keyed[k] >> 32)};
  }
  return found;
}

double medianOf(std::vector<double>& v) {
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

MapSpread mapSpread(const core::MarkerMap& map) {
  MapSpread s;
  if (map.size() < 3) return s;
  std::vector<double> v(map.size());
  for (std::size_t i = 0; i < map.size(); ++i) v[i] = map[i].x;
  s.cx = medianOf(v);
  for (std::size_t i = 0; i < map.size(); ++i) v[i] = map[i].y;
  s.cy = medianOf(v);
  for (std::size_t i = 0; i < map.size(); ++i) v[i] = std::hypot(map[i].x - s.cx, map[i].y - s.cy);
  s.spread = medianOf(v);
  return s;
}

long farMarker(const core::MarkerMap& map, const MapSpread& s) {
  if (map.size() < 3 || !(s.spread > 0.0)) return -1;
  const double reach = kFarSpreads * s.spread;
  // At least two markers lie within the spread of the centre: a marker within (K - 1) spreads of
  // it has one of them within K spreads. Only the markers beyond are looked at, in cells of
  // the reach (another marker within the reach is in the same or an adjacent cell).
  std::vector<uint32_t> candidates;
  for (std::size_t i = 0; i < map.size(); ++i)
    if (std::hypot(map[i].x - s.cx, map[i].y - s.cy) > reach - s.spread) candidates.push_back(static_cast<uint32_t>(i));
  if (candidates.empty()) return -1;
  auto cell = [&](double v, double c) {
    return static_cast<int64_t>(std::clamp(std::floor((v - c) / reach), -4e18, 4e18));
  };
  auto key = [](int64_t ix, int64_t iy) { return std::make_pair(ix, iy); };
  std::vector<std::pair<std::pair<int64_t, int64_t>, uint32_t>> cells(map.size());
  for (std::size_t i = 0; i < map.size(); ++i)
    cells[i] = {key(cell(map[i].x, s.cx), cell(map[i].y, s.cy)), static_cast<uint32_t>(i)};
  std::sort(cells.begin(), cells.end());
  for (const uint32_t i : candidates) {
    const core::Marker& m = map[i];
    const int64_t ix = cell(m.x, s.cx), iy = cell(m.y, s.cy);
    bool alone = true;
    for (int64_t dx = -1; dx <= 1 && alone; ++dx)
      for (int64_t dy = -1; dy <= 1 && alone; ++dy) {
        auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(key(ix + dx, iy + dy), uint32_t{0}));
        for (; it != cells.end() && it->first == key(ix + dx, iy + dy) && alone; ++it)
          alone = it->second == i || std::hypot(map[it->second].x - m.x, map[it->second].y - m.y) > reach;
      }
    if (alone) return i;  // candidates are in map order: the first in the file
  }
  return -1;
}

core::MarkerMap loadMap(const std::string& path) {
  auto in = openWithHeader(path, "id,x,y");
  core::MarkerMap map;
  std::vector<uint32_t> lines;  ///< the line of each marker
  std::string line, why;
  std::vector<double> v;
  int64_t lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line == "\r") continue;
    if (!parseRow(line, 3, v, why)) throw std::runtime_error(fmt::format("'{}': line {}: {}", path, lineno, why));
    if (v[0] < 0 || v[0] != std::floor(v[0]) || v[0] > 2e9)
      throw std::runtime_error(fmt::format("'{}': line {}: id must be an integer >= 0, got {}", path, lineno, v[0]));
    map.push_back({static_cast<int>(v[0]), v[1], v[2]});
    lines.push_back(static_cast<uint32_t>(std::min<int64_t>(lineno, UINT32_MAX)));
  }
  if (const Duplicate d = firstDuplicate(map, lines); d.again > 0)
    throw std::runtime_error(fmt::format("'{}': line {}: duplicate id {} (first on line {})", path, d.again, d.id, d.first));
  const MapSpread s = mapSpread(map);
  if (const long far = farMarker(map, s); far >= 0) {
    const core::Marker& m = map[static_cast<std::size_t>(far)];
    throw std::runtime_error(fmt::format(
        "'{}': line {}: marker {} at ({}, {}) is far outside the rest of the map: no other marker within {:.6g} m, "
        "{} times the map's spread ({:.6g} m, the median distance of its markers from their median point ({:.6g}, {:.6g}))",
        path, lines[static_cast<std::size_t>(far)], m.id, m.x, m.y, kFarSpreads * s.spread, kFarSpreads, s.spread, s.cx, s.cy));
  }
  return map;
}

void writeMap(const std::string& path, const core::MarkerMap& map) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot create '" + path + "'");
  out << "id,x,y\n";
  // fmt's "{}" is the shortest text that reads back to the same double: a map written and read
  // again is the same map, bit for bit.
  for (const auto& m : map) out << fmt::format("{},{},{}\n", m.id, m.x, m.y);
  if (!out) throw std::runtime_error("cannot write '" + path + "'");
}

}  // namespace lcmloc::app::csv
