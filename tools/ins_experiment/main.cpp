// lcmloc-ins-experiment: §II of Wang & Wang (seeds/004) as a scenario (in process, the models of
// lcmloc-ins-sim and the fusion engine of lcmloc-fusion): odometer scale-error estimate over
// time (Fig. 1) and position error of the calibrated odometry/INS against the traditional
// integration (Fig. 2), for a hard start and a gentle start. Optionally writes the sensor log of
// the first run (GROUND_TRUTH, IMU, ODOMETRY) for lcmloc-replay.
#include <filesystem>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/ins_experiment/experiment.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-ins-experiment: odometry/INS scale calibration vs traditional integration (seeds/004 §II)"};
  common::CommonOptions opts;
  opts.config = common::configDir() + "/ins_paper.yaml";
  common::addCommonOptions(app, opts);
  std::string out = "out/ins", log;
  std::vector<std::string> starts{"hard", "gentle"};
  double duration = 0;
  uint64_t seed = 0;
  ins_experiment::Options eo;
  app.add_option("--out", out, "output directory")->capture_default_str();
  app.add_option("--starts", starts, "runs: start profiles (hard, gentle, gentle_turn, gentle_stopgo, steady)")->delimiter(',')->capture_default_str();
  app.add_option("--duration", duration, "override ins_sim.duration [s]")->check(CLI::Range(common::kInsSimDuration.lo, common::kInsSimDuration.hi));
  app.add_option("--seed", seed, "override ins_sim.seed")
      ->check(lcmloc::common::seed());
  app.add_option("--calibration-stage", eo.calibration_stage,
                 "dead reckoning freezes the scale estimate this long after the start [s]")
      ->capture_default_str()
      ->check(lcmloc::common::nonNegative());
  app.add_flag("--fixes", eo.fixes,
               "three-landmark fixes: lcmloc-vision's model (config `vision`, top-level `landmarks`) "
               "re-initializes both filters; the report gives the error before/after each fix");
  app.add_option("--log", log, "write the sensor log of the first run (GROUND_TRUTH, IMU, ODOMETRY) to this file");

  return common::runProcess(app, argc, argv, opts, "lcmloc-ins-experiment", [&] {
    auto cfg = common::loadSystemConfig(opts.config);
    common::prepareOutputDir(out);
    auto ic = cfg.ins_sim;
    if (duration > 0) ic.duration = duration;
    if (seed) ic.seed = seed;
    if (eo.fixes) {
      if (cfg.scenario.landmarks.empty())
        throw common::ConfigError(cfg.file, "landmarks", "--fixes needs a landmark map (list of {id, x, y})");
      eo.vision = cfg.scenario.vision;
      eo.landmarks = cfg.scenario.landmarks;
      eo.fix = cfg.fusion.fix;
      eo.fix_gate = cfg.fusion.fix_gate;
      eo.vision_seed = cfg.scenario.vision.seed ? cfg.scenario.vision.seed
                                                : models::componentSeed(cfg.scenario.seed, "vision");
    }
    std::vector<ins_experiment::RunResult> runs;
    for (std::size_t i = 0; i < starts.size(); ++i) {
      const std::string& s = starts[i];
      if (!models::insStartValid(s)) {
        spdlog::error("--starts: unknown start '{}' (valid: hard, gentle, gentle_turn, gentle_stopgo, steady)", s);
        return common::kExitConfigError;
      }
      models::InsSimConfig c = ic;
      c.start = s;
      std::unique_ptr<lcm::LogFile> lf;
      int64_t ev = 0, truth_seq = 0, imu_seq = 0, odo_seq = 0;
      ins_experiment::StepSink sink;
      if (i == 0 && !log.empty()) {
        const auto parent = std::filesystem::path(log).parent_path();
        if (!parent.empty()) std::filesystem::create_directories(parent);
        lf = std::make_unique<lcm::LogFile>(log, "w");
        if (!lf->good()) throw std::runtime_error("cannot create '" + log + "'");
        sink = [&](const models::InsSimStep& st) {
          auto write = [&](const std::string& ch, const auto& msg, int64_t utime) {
            std::vector<uint8_t> buf(msg.getEncodedSize());
            msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
            lcm::LogEvent le;
            le.eventnum = ev++;
            le.timestamp = utime;
            le.channel = ch;
            le.datalen = static_cast<int32_t>(buf.size());
            le.data = buf.data();
            if (lf->writeEvent(&le) != 0) throw std::runtime_error("cannot write '" + log + "'");
          };
          if (st.odometry) write(cfg.channels.odometry, common::toLcm(*st.odometry, odo_seq++), st.truth.utime);
          if (st.imu) write(cfg.channels.imu, common::toLcm(*st.imu, imu_seq++), st.truth.utime);
          write(cfg.channels.ground_truth, common::toLcm(st.truth, truth_seq++), st.truth.utime);
        };
      }
      const std::string name = s + "_start";
      spdlog::info("run '{}': {:.0f} s, seed {}", name, c.duration, c.seed);
      runs.push_back(ins_experiment::run(name, c, cfg.fusion.filter, cfg.scenario.vehicle.start_utime, eo, sink,
                                         [&](double f) { spdlog::info("  {:.0f} %", f * 100); }));
      if (lf) spdlog::info("sensor log: {} ({} events)", log, ev);
    }
    const bool plotted = ins_experiment::writeReport(runs, ic, eo, out);
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
    std::printf("report: %s/report.json%s\n", out.c_str(),
                plotted ? ", figures fig1_scale.png, fig1b_scale_run.png, fig2_position.png" : " (gnuplot failed: no figures)");
    return common::kExitOk;
  });
}
