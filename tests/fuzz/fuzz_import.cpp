// Fuzz target: the CSV importers. Byte 0 picks one, the rest is split at NUL bytes into files:
//   0  lcmloc-import (importDirectory, every format it tells apart by the header: odometry,
//      landmarks, beacons, gps, ground truth, imu, the map), up to 4 files a.csv .. d.csv, into
//      run.lcmlog and config.yaml; the log it wrote must scan without damage;
//   1  lcmloc-convert mrclam: Robot1_Odometry.dat, Robot1_Measurement.dat,
//      Robot1_Groundtruth.dat, Landmark_Groundtruth.dat, Barcodes.dat;
//   2  lcmloc-convert uwb: Indoor_UWB_Input.txt, Indoor_UWB_GT.txt.
#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "fuzz_util.hpp"
#include "lcmloc/convert/convert.hpp"
#include "lcmloc/import/import.hpp"
#include "lcmloc/logio/log_reader.hpp"

namespace {

/// data split at NUL bytes into the files names[0], names[1], ... in dir (at most names.size()).
void writeFiles(const std::string& dir, const std::vector<std::string>& names, const uint8_t* data, std::size_t size) {
  std::size_t begin = 0;
  for (std::size_t k = 0; k < names.size() && begin <= size; ++k) {
    std::size_t end = begin;
    while (end < size && data[end] != 0) ++end;
    lcmloc::fuzz::writeFile(dir + "/" + names[k], data + begin, end - begin);
    begin = end + 1;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace lcmloc;
  static const bool kQuiet = (fuzz::quiet(), true);
  (void)kQuiet;
  if (size < 1) return 0;
  const uint8_t mode = data[0] % 3;
  const std::string in = fuzz::freshDir("in"), out = fuzz::freshDir("out");
  const std::string in_name = in.substr(fuzz::scratchDir().string().size() + 1);
  try {
    if (mode == 0) {
      writeFiles(in_name, {"a.csv", "b.csv", "c.csv", "d.csv"}, data + 1, size - 1);
      import::ImportOptions opt;
      opt.dir = in;
      opt.out_dir = out;
      opt.fit_noise = false;
      opt.wheelbase = 2.5;
      const auto r = import::importDirectory(opt);
      if (!r.log_path.empty() && logio::scanLog(r.log_path, [](const logio::RawEvent&) {}).damaged)
        fuzz::finding("lcmloc-import wrote a damaged log");
    } else if (mode == 1) {
      writeFiles(in_name,
                 {"Robot1_Odometry.dat", "Robot1_Measurement.dat", "Robot1_Groundtruth.dat",
                  "Landmark_Groundtruth.dat", "Barcodes.dat"},
                 data + 1, size - 1);
      convert::convertMrclam(in, 1, out);
    } else {
      writeFiles(in_name, {"Indoor_UWB_Input.txt", "Indoor_UWB_GT.txt"}, data + 1, size - 1);
      convert::convertUwbLabyrinth(in, out);
    }
  } catch (const std::exception& e) {
    fuzz::refused(e);
  }
  return 0;
}
