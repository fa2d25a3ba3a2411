// lcmloc-magnet-grid: imports the magnet-grid runs (encoder counts + reed byte) and replays them
// with the gated ruler UKF: gate and innovation statistics, track over the grid.
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/import/magnet_grid.hpp"
#include "lcmloc/eval/report.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-magnet-grid: the magnet-grid runs of ../shared/data/magnet_grid_ecn. For each run: import (encoder "
      "counts -> differential-drive ODOMETRY, reed byte -> one MAGRULER detection per magnet pass with its lateral "
      "offset, the 55 mm grid -> map.csv, config.yaml), replay with the gated ruler UKF (and a dead-reckoning "
      "shadow), write OUT/<run>/report.json and track.png; OUT/summary.json over the runs. docs/magnet_grid.md."};
  common::CommonOptions opts;
  common::addOfflineOptions(app, opts,
                            "system YAML file (checked when given; unused otherwise: each run writes its own config.yaml)");
  import::MagnetGridOptions mo;
  std::string data = LCMLOC_MAGNET_GRID_DIR, out = "out/magnet_grid";
  std::vector<std::string> runs;
  bool import_only = false;
  std::vector<double> pv, pw;
  app.add_option("--data", data, "data directory (<run>.txt files)")->capture_default_str();
  app.add_option("--run", runs, "run name(s) (default: all six) or paths to run files");
  app.add_option("-o,--output", out, "output directory")->capture_default_str();
  app.add_flag("--import-only", import_only, "only write OUT/<run>/run.lcmlog, map.csv, config.yaml (for lcmloc-replay)");
  app.add_option("--bit0", mo.bit0, "side of reed bit 0: right or left")->capture_default_str()
      ->check(CLI::IsMember({"right", "left"}));
  app.add_option("--filter", mo.filter, "filter type of config.yaml")->capture_default_str();
  std::optional<double> grid_angle;
  app.add_option("--grid-angle", grid_angle,
                 "grid axes vs the start heading [rad] (default 0; pi/4 for diagonal45degrees, which starts at 45 "
                 "degrees to the grid)");
  app.add_option("--pv-diag", pv, "detection noise: range [m^2], bearing [rad^2]")->expected(2);
  app.add_option("--pw-diag", pw, "process noise per pw_distance: x, y [m^2], theta [rad^2]")->expected(3);
  app.add_option("--pw-turn", mo.pw_turn, "heading variance per radian turned [rad^2/rad]")->capture_default_str();
  app.add_option("--reach", mo.reach, "association window beyond the reed row [m]")->capture_default_str();

  return common::runProcess(app, argc, argv, opts, "lcmloc-magnet-grid", [&]() -> int {
    if (!opts.config.empty()) common::loadSystemConfig(opts.config);
    if (pv.size() == 2) mo.pv_diag = core::Vec2(pv[0], pv[1]);
    if (pw.size() == 3) mo.pw_diag = core::Vec3(pw[0], pw[1], pw[2]);
    if (runs.empty())
      runs = {"line1magnet", "line2magnets", "diagonal45degrees", "circles", "oneloop", "twoloops"};
    // Each run's input file and output name (OUT/<name>), all before anything is written: two
    // runs of one name would write the same directory and summary entry.
    std::vector<std::pair<std::string, std::string>> inputs;  // (input file, name)
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const std::string& run = runs[i];
      const bool path = run.find('/') != std::string::npos || run.find(".txt") != std::string::npos;
      const std::string input = path ? run : data + "/" + run + ".txt";
      const std::string name = std::filesystem::path(input).stem().string();
      for (std::size_t k = 0; k < i; ++k)
        if (inputs[k].second == name)
          throw common::ConfigError("--run", "",
                                    fmt::format("'{}' and '{}' are both run '{}' (output {}/{}): give each run once, "
                                                "or copy one under another name",
                                                runs[k], run, name, out, name));
      inputs.emplace_back(input, name);
    }
    nlohmann::json summary;
    for (const auto& [input, name] : inputs) {
      mo.input = input;
      mo.name = name;
      mo.out_dir = out + "/" + mo.name;
      mo.grid_angle = grid_angle ? *grid_angle : mo.name == "diagonal45degrees" ? 0.7853981633974483 : 0.0;
      if (import_only) {
        const auto r = import::importMagnetGrid(mo);
        std::cout << fmt::format(
            "{}: {} rows, {} refused, {} odometry, {} magnet passes, {:.2f} m, {:.1f} rad turned, {} magnets in the "
            "map -> {}, {}, {}\n",
            mo.name, r.rows, r.refused, r.odometry, r.detections.size(), r.distance_m, r.turned_rad, r.map.size(),
            r.log_path, r.map_path, r.config_path);
        for (const auto& [line, why] : r.refusals) std::cout << fmt::format("refused {}:{}: {}\n", mo.input, line, why);
        continue;
      }
      import::MagnetGridImport r;
      const auto rep = import::runMagnetGrid(mo, &r);
      std::cout << fmt::format(
          "{}: {:.2f} m, {:.1f} rad turned, {} passes: {} accepted, {} gate-rejected, {} without candidate, {} "
          "lockouts; NIS mean {:.2f} (dof 2), median {:.2f} (1.39), within gate {:.3f} (0.99), within 95% {:.3f} "
          "(0.95); {} magnets; max prior sigma {:.1f} mm; final sigma xy {:.1f} mm; {} refused rows -> {}/track.png\n",
          mo.name, r.distance_m, r.turned_rad, rep.detections, rep.accepted, rep.rejected_gate, rep.no_candidate,
          rep.lockouts, rep.nis_mean, rep.nis_median, rep.within_gate, rep.within_95, rep.distinct_magnets,
          rep.max_prior_sigma * 1e3, rep.final_sigma_xy * 1e3, r.refused, mo.out_dir);
      summary[mo.name] = {{"passes", rep.detections}, {"accepted", rep.accepted}, {"rejected_gate", rep.rejected_gate},
                          {"no_candidate", rep.no_candidate}, {"lockouts", rep.lockouts},
                          {"nis_mean", rep.nis_mean}, {"nis_median", rep.nis_median},
                          {"within_gate", rep.within_gate}, {"within_95", rep.within_95},
                          {"distinct_magnets", rep.distinct_magnets}, {"distance_m", r.distance_m},
                          {"max_prior_sigma_m", rep.max_prior_sigma},
                          {"refused_rows", r.refused}};
    }
    if (!import_only) {
      std::filesystem::create_directories(out);
      eval::writeJson(summary, out + "/summary.json");
    }
    return common::kExitOk;
  });
}
