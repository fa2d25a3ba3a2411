#pragma once
// Converters of other people's recordings into the import format (docs/import_formats.md), so
// that lcmloc-import reads them like any user's CSV directory. Each reads the data set's own
// files unchanged, refuses a malformed line naming file and line, and writes the CSV files of
// the kinds the recording holds. What the data set's documentation leaves open is converted as
// written and said in the result's notes, not fixed up with constants.
#include <string>
#include <vector>

namespace lcmloc::convert {

/// What a conversion wrote.
struct Converted {
  struct File {
    std::string name;   ///< file name in the output directory
    std::string kind;   ///< odometry, landmarks, beacons, ground truth, map
    long rows = 0;
  };
  std::vector<File> files;
  std::vector<std::string> notes;  ///< what the user should know (rows left out and why)
};

/// UTIAS MRCLAM (one robot of a data set directory): RobotN_Odometry.dat (time, v, w) ->
/// odometry.csv (time,speed,yaw_rate); RobotN_Measurement.dat (time, barcode, range, bearing)
/// -> landmarks.csv, a barcode of a landmark (Barcodes.dat, subjects 6-20) as its subject id,
/// of another robot (subjects 1-5) as `unknown` (a moving robot is no map landmark: an
/// observation without identity, for the data association to refuse); RobotN_Groundtruth.dat
/// -> truth.csv (time,x,y,heading); Landmark_Groundtruth.dat -> map.csv. A measurement of a
/// barcode the table lacks is left out (counted in notes). Throws std::runtime_error naming the
/// file and line of a malformed line.
Converted convertMrclam(const std::string& dir, int robot, const std::string& out_dir);

/// TU Chemnitz UWB "Labyrinth" (Indoor_UWB_Input.txt, Indoor_UWB_GT.txt in dir): range2 rows ->
/// beacons.csv (time,beacon_id,range,range_std with sigma = sqrt(variance)); the module
/// positions the rows carry -> map.csv (one module at two positions is an error); odom2diff rows
/// (time, right and left wheel speed, lateral speed, wheel distance b, variances) ->
/// odometry.csv (time,speed,yaw_rate: (vr + vl) / 2, (vr - vl) / b); point2 rows -> truth.csv
/// (time,truth_x,truth_y: position only). Throws std::runtime_error naming file and line.
Converted convertUwbLabyrinth(const std::string& dir, const std::string& out_dir);

}  // namespace lcmloc::convert
