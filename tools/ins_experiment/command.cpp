// lcmloc-ins-experiment's work after its command line (command.hpp).
#include "lcmloc/ins_experiment/command.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"

namespace lcmloc::ins_experiment {

int runCommand(const simconfig::SimSystemConfig& cfg, const CommandOptions& o) {
  Options eo = o.experiment;
  app::refuseExistingOutput(o.log, o.overwrite, "--log");
  app::prepareOutputDir(o.output, o.overwrite);
  auto ic = cfg.ins_sim;
  if (o.duration > 0) ic.duration = o.duration;
  if (o.seed) ic.seed = o.seed;
  if (eo.fixes) {
    if (cfg.scenario.landmarks.empty())
      throw app::ConfigError(cfg.file, "landmarks", "--fixes needs a landmark map (list of {id, x, y})");
    eo.vision = cfg.scenario.vision;
    eo.landmarks = cfg.scenario.landmarks;
    eo.fix = cfg.fusion.fix;
    eo.fix_gate = cfg.fusion.fix_gate;
    eo.vision_seed = cfg.scenario.vision.seed ? cfg.scenario.vision.seed
                                              : sim::componentSeed(cfg.scenario.seed, "vision");
  }
  std::vector<RunResult> runs;
  for (std::size_t i = 0; i < o.starts.size(); ++i) {
    const std::string& s = o.starts[i];
    if (!sim::insStartValid(s)) {
      spdlog::error("--starts: unknown start '{}' (valid: hard, gentle, gentle_turn, gentle_stopgo, steady)", s);
      return app::kExitConfigError;
    }
    sim::InsSimConfig c = ic;
    c.start = s;
    std::unique_ptr<lcm::LogFile> lf;
    int64_t ev = 0, truth_seq = 0, imu_seq = 0, odo_seq = 0;
    StepSink sink;
    if (i == 0 && !o.log.empty()) {
      const auto parent = std::filesystem::path(o.log).parent_path();
      if (!parent.empty()) std::filesystem::create_directories(parent);
      lf = std::make_unique<lcm::LogFile>(o.log, "w");
      if (!lf->good()) throw std::runtime_error("cannot create '" + o.log + "'");
      sink = [&](const sim::InsSimStep& st) {
        auto write = [&](const std::string& ch, const auto& msg, int64_t utime) {
          std::vector<uint8_t> buf(msg.getEncodedSize());
          msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
          lcm::LogEvent le;
          le.eventnum = ev++;
          le.timestamp = utime;
          le.channel = ch;
          le.datalen = static_cast<int32_t>(buf.size());
          le.data = buf.data();
          if (lf->writeEvent(&le) != 0) throw std::runtime_error("cannot write '" + o.log + "'");
        };
        if (st.odometry) write(cfg.channels.odometry, drivers::toLcm(*st.odometry, odo_seq++), st.truth.utime);
        if (st.imu) write(cfg.channels.imu, drivers::toLcm(*st.imu, imu_seq++), st.truth.utime);
        write(cfg.channels.ground_truth, drivers::toLcm(st.truth, truth_seq++), st.truth.utime);
      };
    }
    const std::string name = s + "_start";
    spdlog::info("run '{}': {:.0f} s, seed {}", name, c.duration, c.seed);
    runs.push_back(run(name, c, cfg.fusion.filter, cfg.scenario.vehicle.start_utime, eo, sink,
                                       [&](double f) { spdlog::info("  {:.0f} %", f * 100); }));
    if (lf) spdlog::info("sensor log: {} ({} events)", o.log, ev);
  }
  const bool plotted = writeReport(runs, ic, eo, o.output);
  std::printf("%-20s %9s %10s %12s %12s %9s %10s %12s %12s %12s %12s\n", "run", "dist[km]", "|dK|first",
              "|dK|10s", "sigma10s", "t_1ord[s]", "|dK|final", "odo_ins[m]", "uncal[m]", "dr_cal[m]",
              "dr_trad[m]");
  for (const auto& r : runs)
    std::printf("%-20s %9.2f %10.2e %12.2e %12.2e %9.1f %10.2e %12.2f %12.2f %12.2f %12.2f\n", r.name.c_str(),
                r.distance_m / 1000, r.k_err_at_start, r.k_err_10s, r.k_std_10s, r.t_one_order_s, r.k_err_final,
                r.final_err_cal, r.final_err_uncal, r.final_err_dr_cal, r.final_err_dr_uncal);
  for (const auto& r : runs) {
    if (!eo.fixes) break;
    if (r.fixes.empty()) {
      std::printf("%-20s no fix (three landmarks never in view)\n", r.name.c_str());
      continue;
    }
    const auto& f = r.fixes.front();
    double worst = 0;
    for (const auto& p : r.fixes) worst = std::max(worst, p.after_cal);
    std::printf("%-20s %zu fixes (%d refused), first at t = %.1f s: odo_ins %.3f -> %.3f m, odo_ins_uncal %.3f -> "
                "%.3f m; worst after a fix %.3f m\n",
                r.name.c_str(), r.fixes.size(), r.fix_refused, f.t, f.before_cal, f.after_cal, f.before_uncal,
                f.after_uncal, worst);
  }
  std::printf("report: %s/report.json%s\n", o.output.c_str(),
              plotted ? ", figures fig1_scale.png, fig1b_scale_run.png, fig2_position.png" : " (gnuplot failed: no figures)");
  return app::kExitOk;
}

}  // namespace lcmloc::ins_experiment
