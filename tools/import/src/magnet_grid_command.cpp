// lcmloc-magnet-grid's work after its command line (magnet_grid_command.hpp).
#include "lcmloc/import/magnet_grid_command.hpp"

#include <filesystem>
#include <iostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/eval/report.hpp"

namespace lcmloc::import {

int runMagnetGridCommand(const MagnetGridCommand& c) {
  app::refuseExistingOutput(c.output, c.overwrite);
  MagnetGridOptions mo = c.grid;
  if (c.pv_diag.size() == 2) mo.pv_diag = core::Vec2(c.pv_diag[0], c.pv_diag[1]);
  if (c.pw_diag.size() == 3) mo.pw_diag = core::Vec3(c.pw_diag[0], c.pw_diag[1], c.pw_diag[2]);
  std::vector<std::string> runs = c.runs;
  if (runs.empty())
    runs = {"line1magnet", "line2magnets", "diagonal45degrees", "circles", "oneloop", "twoloops"};
  // Each run's input file and output name (OUT/<name>), all before anything is written: two
  // runs of one name would write the same directory and summary entry.
  std::vector<std::pair<std::string, std::string>> inputs;  // (input file, name)
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::string& run = runs[i];
    const bool path = run.find('/') != std::string::npos || run.find(".txt") != std::string::npos;
    const std::string input = path ? run : c.data + "/" + run + ".txt";
    const std::string name = std::filesystem::path(input).stem().string();
    for (std::size_t k = 0; k < i; ++k)
      if (inputs[k].second == name)
        throw app::ConfigError("--run", "",
                                  fmt::format("'{}' and '{}' are both run '{}' (output {}/{}): give each run once, "
                                              "or copy one under another name",
                                              runs[k], run, name, c.output, name));
    app::requireInputFile(input, "run " + run);
    inputs.emplace_back(input, name);
  }
  nlohmann::json summary;
  for (const auto& [input, name] : inputs) {
    mo.input = input;
    mo.name = name;
    mo.out_dir = c.output + "/" + mo.name;
    mo.grid_angle = c.grid_angle ? *c.grid_angle : mo.name == "diagonal45degrees" ? 0.7853981633974483 : 0.0;
    if (c.import_only) {
      const auto r = importMagnetGrid(mo);
      std::cout << fmt::format(
          "{}: {} rows, {} refused, {} odometry, {} magnet passes, {:.2f} m, {:.1f} rad turned, {} magnets in the "
          "map -> {}, {}, {}\n",
          mo.name, r.rows, r.refused, r.odometry, r.detections.size(), r.distance_m, r.turned_rad, r.map.size(),
          r.log_path, r.map_path, r.config_path);
      for (const auto& [line, why] : r.refusals) std::cout << fmt::format("refused {}:{}: {}\n", mo.input, line, why);
      continue;
    }
    MagnetGridImport r;
    const auto rep = runMagnetGrid(mo, &r);
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
  if (!c.import_only) {
    std::filesystem::create_directories(c.output);
    eval::writeJson(summary, c.output + "/summary.json");
  }
  return app::kExitOk;
}

}  // namespace lcmloc::import
