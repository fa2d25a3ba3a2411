// lcmloc-convert: other people's recordings -> the import format (CSV directory for lcmloc-import).
#include <spdlog/spdlog.h>

#include <filesystem>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/convert/convert.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-convert: converts a public data set's files into the CSV import format (then: lcmloc-import "
               "OUT -o RUN)"};
  app::CommonOptions opts;
  app::addOfflineOptions(app, opts, "unused");
  std::string dir, out;
  bool overwrite = false;
  int robot = 1;
  auto* mrclam = app.add_subcommand("mrclam", "UTIAS MRCLAM: one robot of a data set directory (RobotN_*.dat)");
  mrclam->add_option("--dir", dir, "data set directory")->required();
  mrclam->add_option("--robot", robot, "robot number")->capture_default_str()->check(CLI::Range(1, 5));
  auto* uwb = app.add_subcommand("uwb-labyrinth", "TU Chemnitz UWB Labyrinth (Indoor_UWB_Input.txt, Indoor_UWB_GT.txt)");
  uwb->add_option("--dir", dir, "data set directory")->required();
  for (auto* s : {mrclam, uwb}) {
    app::addOutputOption(*s, out, "output directory (CSV files for lcmloc-import)")->required();
    app::addOverwriteFlag(*s, overwrite);
  }
  app.require_subcommand(1);
  return app::runProcess(app, argc, argv, opts, "lcmloc-convert", [&] {
    if (!std::filesystem::is_directory(dir)) throw app::UsageError("--dir " + dir + ": not a directory");
    app::prepareOutputDir(out, overwrite);
    const auto c = mrclam->parsed() ? convert::convertMrclam(dir, robot, out) : convert::convertUwbLabyrinth(dir, out);
    for (const auto& f : c.files) std::printf("%-16s %-13s %8ld rows\n", f.name.c_str(), f.kind.c_str(), f.rows);
    for (const auto& n : c.notes) std::printf("note: %s\n", n.c_str());
    std::printf("next: lcmloc-import %s -o RUN\n", out.c_str());
    return app::kExitOk;
  });
}
