#include "lcmloc/convert/convert.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <spdlog/fmt/fmt.h>

#include "lcmloc/app/text.hpp"

namespace lcmloc::convert {
namespace {

/// The whitespace-separated lines of a data file, '#' comments and blank lines skipped, each
/// with its line number.
struct Line {
  long number = 0;
  std::vector<std::string> fields;
};

std::vector<Line> readTable(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("'" + path + "': cannot be opened");
  std::vector<Line> lines;
  std::string text;
  long n = 0;
  while (std::getline(in, text)) {
    ++n;
    const auto hash = text.find('#');
    if (hash != std::string::npos) text.erase(hash);
    std::istringstream words(text);
    Line l{n, {}};
    for (std::string w; words >> w;) l.fields.push_back(w);
    if (!l.fields.empty()) lines.push_back(std::move(l));
  }
  return lines;
}

[[noreturn]] void bad(const std::string& path, const Line& l, const std::string& why) {
  throw std::runtime_error(path + ":" + std::to_string(l.number) + ": " + why);
}

/// Field i of l as a finite number.
double number(const std::string& path, const Line& l, std::size_t i) {
  if (i >= l.fields.size())
    bad(path, l, "column " + std::to_string(i + 1) + " missing (" + std::to_string(l.fields.size()) + " columns)");
  const std::string& f = l.fields[i];
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(f, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != f.size() || !std::isfinite(v))
    bad(path, l, "column " + std::to_string(i + 1) + ": not a finite number: '" + app::printable(f) + "'");
  return v;
}

/// An integer field (a barcode, an id).
long integer(const std::string& path, const Line& l, std::size_t i) {
  const double v = number(path, l, i);
  if (v != std::floor(v) || std::fabs(v) > 1e9)
    bad(path, l, "column " + std::to_string(i + 1) + ": not an integer: '" + l.fields[i] + "'");
  return static_cast<long>(v);
}

/// Times and values printed so that they read back to the same double.
std::string text(double v) { return fmt::format("{}", v); }

class CsvOut {
 public:
  CsvOut(const std::string& dir, std::string name, std::string kind, const std::string& header)
      : path_(dir + "/" + name), out_(path_), file_{std::move(name), std::move(kind), 0} {
    if (!out_) throw std::runtime_error("'" + path_ + "': cannot be written");
    out_ << header << '\n';
  }
  void row(const std::vector<std::string>& fields) {
    for (std::size_t i = 0; i < fields.size(); ++i) out_ << (i ? "," : "") << fields[i];
    out_ << '\n';
    ++file_.rows;
  }
  Converted::File close() {
    out_.close();
    if (!out_) throw std::runtime_error("'" + path_ + "': write failed");
    return file_;
  }

 private:
  std::string path_;
  std::ofstream out_;
  Converted::File file_;
};

}  // namespace

Converted convertMrclam(const std::string& dir, int robot, const std::string& out_dir) {
  if (robot < 1 || robot > 5) throw std::invalid_argument("robot " + std::to_string(robot) + ": MRCLAM robots are 1-5");
  const std::string r = dir + "/Robot" + std::to_string(robot) + "_";
  Converted c;
  // Subject ids by barcode, and the landmarks' positions.
  std::map<long, long> subject_of;
  const std::string barcodes = dir + "/Barcodes.dat";
  for (const auto& l : readTable(barcodes)) {
    const long subject = integer(barcodes, l, 0), code = integer(barcodes, l, 1);
    if (!subject_of.emplace(code, subject).second) bad(barcodes, l, "barcode " + std::to_string(code) + " twice");
  }
  {
    const std::string path = dir + "/Landmark_Groundtruth.dat";
    CsvOut map(out_dir, "map.csv", "map", "id,x,y");
    for (const auto& l : readTable(path)) {
      const long id = integer(path, l, 0);
      if (id <= 5) bad(path, l, "subject " + std::to_string(id) + " is a robot (1-5), not a landmark");
      map.row({std::to_string(id), text(number(path, l, 1)), text(number(path, l, 2))});
    }
    c.files.push_back(map.close());
  }
  {
    const std::string path = r + "Odometry.dat";
    CsvOut odo(out_dir, "odometry.csv", "odometry", "time,speed,yaw_rate");
    for (const auto& l : readTable(path))
      odo.row({text(number(path, l, 0)), text(number(path, l, 1)), text(number(path, l, 2))});
    c.files.push_back(odo.close());
  }
  {
    const std::string path = r + "Measurement.dat";
    CsvOut obs(out_dir, "landmarks.csv", "landmarks", "time,landmark_id,range,bearing");
    long unknown_code = 0, robots = 0;
    for (const auto& l : readTable(path)) {
      const auto s = subject_of.find(integer(path, l, 1));
      if (s == subject_of.end()) {
        ++unknown_code;
        continue;
      }
      const bool is_robot = s->second <= 5;
      robots += is_robot;
      obs.row({text(number(path, l, 0)), is_robot ? "unknown" : std::to_string(s->second), text(number(path, l, 2)),
               text(number(path, l, 3))});
    }
    c.files.push_back(obs.close());
    c.notes.push_back(std::to_string(robots) + " observations of other robots written without identity (unknown)");
    if (unknown_code)
      c.notes.push_back(std::to_string(unknown_code) + " measurements of a barcode Barcodes.dat lacks left out");
  }
  {
    const std::string path = r + "Groundtruth.dat";
    CsvOut truth(out_dir, "truth.csv", "ground truth", "time,x,y,heading");
    for (const auto& l : readTable(path))
      truth.row({text(number(path, l, 0)), text(number(path, l, 1)), text(number(path, l, 2)), text(number(path, l, 3))});
    c.files.push_back(truth.close());
  }
  return c;
}

Converted convertUwbLabyrinth(const std::string& dir, const std::string& out_dir) {
  Converted c;
  const std::string input = dir + "/Indoor_UWB_Input.txt", gt = dir + "/Indoor_UWB_GT.txt";
  std::map<long, std::pair<double, double>> modules;
  CsvOut ranges(out_dir, "beacons.csv", "beacons", "time,beacon_id,range,range_std");
  CsvOut odo(out_dir, "odometry.csv", "odometry", "time,speed,yaw_rate");
  double wheel_distance = 0;
  for (const auto& l : readTable(input)) {
    const std::string& kind = l.fields.front();
    if (kind == "range2") {
      const double var = number(input, l, 3);
      if (var <= 0) bad(input, l, "range variance " + l.fields[3] + " is not positive");
      const long id = integer(input, l, 6);
      const std::pair<double, double> at{number(input, l, 4), number(input, l, 5)};
      const auto [m, added] = modules.emplace(id, at);
      if (!added && m->second != at) bad(input, l, "module " + std::to_string(id) + " at a second position");
      ranges.row({text(number(input, l, 1)), std::to_string(id), text(number(input, l, 2)), text(std::sqrt(var))});
    } else if (kind == "odom2diff") {
      const double vr = number(input, l, 2), vl = number(input, l, 3), b = number(input, l, 5);
      if (b <= 0) bad(input, l, "wheel distance " + l.fields[5] + " is not positive");
      wheel_distance = b;
      odo.row({text(number(input, l, 1)), text(0.5 * (vr + vl)), text((vr - vl) / b)});
    } else {
      bad(input, l, "unknown row type '" + app::printable(kind) + "' (range2, odom2diff)");
    }
  }
  c.files.push_back(ranges.close());
  c.files.push_back(odo.close());
  {
    CsvOut map(out_dir, "map.csv", "map", "id,x,y");
    for (const auto& [id, at] : modules) map.row({std::to_string(id), text(at.first), text(at.second)});
    c.files.push_back(map.close());
  }
  {
    CsvOut truth(out_dir, "truth.csv", "ground truth", "time,truth_x,truth_y");
    for (const auto& l : readTable(gt)) {
      if (l.fields.front() != "point2") bad(gt, l, "unknown row type '" + app::printable(l.fields.front()) + "' (point2)");
      truth.row({text(number(gt, l, 1)), text(number(gt, l, 2)), text(number(gt, l, 3))});
    }
    c.files.push_back(truth.close());
  }
  c.notes.push_back("yaw rate = (right - left wheel speed) / wheel distance " + text(wheel_distance) +
                    " m as the data set gives it: compare the heading with the truth's direction of travel");
  return c;
}

}  // namespace lcmloc::convert
