#include "lcmloc/app/csv.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <set>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "lcmloc/app/files.hpp"

namespace lcmloc::common::csv {

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

core::MarkerMap loadMap(const std::string& path) {
  auto in = openWithHeader(path, "id,x,y");
  core::MarkerMap map;
  std::set<int> ids;
  std::string line, why;
  std::vector<double> v;
  int64_t lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line == "\r") continue;
    if (!parseRow(line, 3, v, why)) throw std::runtime_error(fmt::format("'{}': line {}: {}", path, lineno, why));
    if (v[0] < 0 || v[0] != std::floor(v[0]) || v[0] > 2e9)
      throw std::runtime_error(fmt::format("'{}': line {}: id must be an integer >= 0, got {}", path, lineno, v[0]));
    const int id = static_cast<int>(v[0]);
    if (!ids.insert(id).second)
      throw std::runtime_error(fmt::format("'{}': line {}: duplicate id {}", path, lineno, id));
    map.push_back({id, v[1], v[2]});
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

}  // namespace lcmloc::common::csv
