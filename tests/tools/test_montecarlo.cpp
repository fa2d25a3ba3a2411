// lcmloc-montecarlo from the command line: the layout and process-noise overrides reach the runs
// and the report, and bad values are refused before any run.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "run_command.hpp"

namespace fs = std::filesystem;

namespace {

class MonteCarloCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("lcmloc_test_montecarlo_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::pair<int, std::string> run(const std::string& args) {
    return runCommand(LCMLOC_MONTECARLO_BIN, args + " --overwrite -o '" + (dir_ / "report.json").string() + "'", dir_);
  }
  nlohmann::json report() const {
    std::ifstream f(dir_ / "report.json");
    return nlohmann::json::parse(f);
  }
  fs::path dir_;
};

}  // namespace

TEST_F(MonteCarloCommand, MarkerSpacingAndProcessNoiseOverrideTheConfig) {
  const std::string oval = std::string(" --config ") + LCMLOC_OVAL_YAML;
  // As configured: the oval's 157 markers 2 m apart and the paper's Pw.
  auto [rc, out] = run(oval + " --runs 1 --filters ukf_gated");
  ASSERT_EQ(rc, 0) << out;
  auto j = report();
  EXPECT_EQ(j["markers"]["count"], 157);
  EXPECT_EQ(j["markers"]["spacing_m"], 2.0);
  EXPECT_EQ(j["pw_diag"], nlohmann::json::array({1e-4, 1e-4, 8.73e-3}));
  EXPECT_EQ(j["filters"]["ukf_gated"]["accepted"], 157);  // every marker seen once (no fault passes)
  const double rmse_paper = j["filters"]["ukf_gated"]["rmse_m"]["median"];

  std::tie(rc, out) = run(oval + " --runs 1 --filters ukf_gated --marker-spacing 10 --pw-diag 1e-3,1e-3,1e-3");
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("32 markers 10 m apart, Pw (0.001, 0.001, 0.001)"), std::string::npos) << out;
  j = report();
  EXPECT_EQ(j["markers"]["count"], 32);
  EXPECT_EQ(j["markers"]["spacing_m"], 10.0);
  EXPECT_EQ(j["pw_diag"], nlohmann::json::array({1e-3, 1e-3, 1e-3}));
  EXPECT_EQ(j["filters"]["ukf_gated"]["accepted"], 32);
  // Five times fewer markers: the estimate is worse than with every 2 m.
  EXPECT_GT(j["filters"]["ukf_gated"]["rmse_m"]["median"].get<double>(), 3.0 * rmse_paper);

  std::tie(rc, out) = run(oval + " --runs 2 --filters ukf_gated --seed-base 18446744073709551614");
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("(seeds 18446744073709551614..18446744073709551615)"), std::string::npos) << out;
  EXPECT_EQ(report()["seed_base"], 18446744073709551614ULL);
}

TEST_F(MonteCarloCommand, BadOverridesAreRefusedWithTheirReason) {
  const std::pair<std::string, std::string> cases[] = {
      {"--marker-spacing 0", "--marker-spacing: 0 is not > 0"},
      {"--marker-spacing abc", "--marker-spacing"},
      {"--marker-spacing 0.0001", "380001 markers 0.0001 m apart: more than markers.count allows (100000)"},
      {"--pw-diag 1e-3,1e-3", "--pw-diag"},
      {"--pw-diag 1e-3,-1,1e-3", "--pw-diag: -1 is not >= 0"},
      {"--pw-diag 1e-3,nan,1e-3", "nan"},
      // a uint64 option reads "-1" as 2^64 - 1; it was taken as "no seed given" here
      {"--seed-base -1", "--seed-base: -1 is not a seed"},
      {"--filters ukf_gated,ukf_gated", "--filters: filters[1]: 'ukf_gated' is listed twice"},
      {"--filters ukf_gated,bogus", "--filters: filters[1]: unknown filter type 'bogus'"},
      {"--seed-base 2.5", "--seed-base: 2.5 is not a seed"},
  };
  for (const auto& [args, why] : cases) {
    const auto [rc, out] = run("--runs 1 " + args);
    EXPECT_EQ(rc, 2) << args << "\n" << out;
    EXPECT_NE(out.find(why), std::string::npos) << args << "\n" << out;
    EXPECT_FALSE(fs::exists(dir_ / "report.json")) << args;
  }
}
