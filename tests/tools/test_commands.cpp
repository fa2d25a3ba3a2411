// The tools' work behind their thin mains, called as functions: lcmloc-ctl's command building,
// lcmloc-replay's config overrides and refusals, the experiments' refusal of an existing output
// before any work.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/ctl/control.hpp"
#include "lcmloc/ins_experiment/command.hpp"
#include "lcmloc/landmark_experiment/command.hpp"
#include "lcmloc/replay/command.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

TEST(CtlCommand, ParamsBecomeANestedYamlMap) {
  const YAML::Node n = YAML::Load(ctl::paramsToYaml({"gate.value=6.635", "pv_diag=[0.01, 0.02]", "name=x"}));
  EXPECT_DOUBLE_EQ(n["gate"]["value"].as<double>(), 6.635);
  ASSERT_EQ(n["pv_diag"].size(), 2u);
  EXPECT_DOUBLE_EQ(n["pv_diag"][1].as<double>(), 0.02);
  EXPECT_EQ(n["name"].as<std::string>(), "x");
  EXPECT_THROW(ctl::paramsToYaml({"novalue"}), CLI::ValidationError);
  EXPECT_THROW(ctl::paramsToYaml({"=1"}), CLI::ValidationError);
}

TEST(CtlCommand, EachSubcommandMakesItsControlMessage) {
  ctl::Command c;
  c.kind = ctl::Command::SetPose;
  c.pose = {1.0, 2.0, 0.5};
  auto m = ctl::makeCommand(c);
  EXPECT_EQ(m.command, lcmloc::fusion_control_t::CMD_SET_POSE);
  EXPECT_DOUBLE_EQ(m.pose[1], 2.0);
  EXPECT_DOUBLE_EQ(m.pose_std[2], 0.05);  // the default 1-sigma of theta
  c.kind = ctl::Command::Switch;
  c.filter = "ukf";
  c.params = {"gate.value=9"};
  m = ctl::makeCommand(c);
  EXPECT_EQ(m.command, lcmloc::fusion_control_t::CMD_SWITCH_FILTER);
  EXPECT_EQ(m.filter, "ukf");
  EXPECT_DOUBLE_EQ(YAML::Load(m.parameters)["gate"]["value"].as<double>(), 9.0);
  c.params_yaml = "{gate: {value: 6}}";
  EXPECT_THROW(ctl::makeCommand(c), CLI::ValidationError);  // --param and --params, not both
  c.kind = ctl::Command::Reset;
  EXPECT_EQ(ctl::makeCommand(c).command, lcmloc::fusion_control_t::CMD_RESET);
  EXPECT_NE(ctl::kExitRefused, app::kExitInputDamaged);  // its own codes come after the shared ones
  EXPECT_GT(ctl::kExitNoAnswer, app::kExitInputDamaged);
}

TEST(ReplayCommand, OverridesTheFilterAndTheShadows) {
  simconfig::SimSystemConfig cfg;
  cfg.fusion.shadow = {"dead_reckoning"};
  replay::CommandOptions o;
  o.filter = "ukf";
  o.shadow = "dead_reckoning,,ukf_gated";
  auto c = replay::applyOverrides(cfg, o);
  EXPECT_EQ(c.fusion.filter.type, "ukf");
  EXPECT_EQ(c.fusion.shadow, (std::vector<std::string>{"dead_reckoning", "ukf_gated"}));
  o = {};
  o.no_shadow = true;
  EXPECT_TRUE(replay::applyOverrides(cfg, o).fusion.shadow.empty());
  o = {};
  o.filter = "no_such_filter";
  EXPECT_THROW(replay::applyOverrides(cfg, o), app::ConfigError);
}

TEST(ReplayCommand, RefusesAMissingInputAndAnExistingOutput) {
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_replay_cmd_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "in.lcmlog") << "";
  std::ofstream(dir / "out.lcmlog") << "kept";
  const simconfig::SimSystemConfig cfg;
  replay::CommandOptions o;
  EXPECT_THROW(replay::runCommand(cfg, o), app::UsageError);  // neither given
  o.input = (dir / "missing.lcmlog").string();
  o.output = (dir / "new.lcmlog").string();
  EXPECT_THROW(replay::runCommand(cfg, o), app::UsageError);
  o.input = (dir / "in.lcmlog").string();
  o.output = (dir / "out.lcmlog").string();
  EXPECT_THROW(replay::runCommand(cfg, o), app::UsageError);
  std::ifstream in(dir / "out.lcmlog");
  std::string kept;
  in >> kept;
  EXPECT_EQ(kept, "kept");
  EXPECT_FALSE(fs::exists(dir / "new.lcmlog"));
  fs::remove_all(dir);
}

TEST(ExperimentCommands, RefuseAnExistingOutputBeforeAnyWork) {
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_exp_cmd_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "report.json") << "{}";
  const auto before = fs::last_write_time(dir / "out" / "report.json");
  const simconfig::SimSystemConfig cfg;
  landmark_experiment::CommandOptions lo;
  lo.output = (dir / "out").string();
  lo.experiment.runs = 1;
  EXPECT_THROW(landmark_experiment::runCommand(cfg, lo), app::UsageError);
  ins_experiment::CommandOptions io;
  io.output = (dir / "out").string();
  io.duration = 1;
  EXPECT_THROW(ins_experiment::runCommand(cfg, io), app::UsageError);
  io.output = (dir / "fresh").string();
  io.log = (dir / "out" / "report.json").string();  // an existing --log
  EXPECT_THROW(ins_experiment::runCommand(cfg, io), app::UsageError);
  EXPECT_FALSE(fs::exists(dir / "fresh"));
  EXPECT_EQ(fs::last_write_time(dir / "out" / "report.json"), before);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "out"), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}
