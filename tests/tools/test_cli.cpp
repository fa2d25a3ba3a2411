// One command-line grammar for every program: --help and --version exit 0, --help states the
// exit codes, --version prints the program's name and the project's version; and no program
// replaces an existing output without --overwrite (exit 2, the output untouched), and replaces
// it with --overwrite.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "run_command.hpp"
#include "temp_files.hpp"

namespace fs = std::filesystem;

namespace {

/// (name, path) of every program the build makes (LCMLOC_PROGRAMS_FILE: "name path" lines).
std::vector<std::pair<std::string, std::string>> programs() {
  std::vector<std::pair<std::string, std::string>> out;
  std::ifstream in(LCMLOC_PROGRAMS_FILE);
  std::string name, path;
  while (in >> name >> path) out.emplace_back(name, path);
  return out;
}

std::string program(const std::string& name) {
  for (const auto& [n, p] : programs())
    if (n == name) return p;
  return "";
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

fs::path tempDir(const std::string& name) { return freshTempDir("lcmloc_cli_", name); }

constexpr const char* kFooter = "Exit status: 0 ok, 1 runtime error, 2 usage or configuration error";

}  // namespace

TEST(CommandLine, EveryProgramHasHelpWithTheExitCodesAndVersion) {
  const auto all = programs();
  // The programs of drivers/, fusion/, logger/ and tools/ (25 when this was written).
  ASSERT_GE(all.size(), 20u) << "programs listed in " << LCMLOC_PROGRAMS_FILE;
  const fs::path dir = tempDir("help");
  for (const auto& [name, path] : all) {
    SCOPED_TRACE(name);
    auto [rc, out] = runCommand(path, "--help", dir);
    EXPECT_EQ(rc, 0) << out;
    EXPECT_NE(out.find(kFooter), std::string::npos) << out;
    EXPECT_NE(out.find("--version"), std::string::npos) << out;
    std::tie(rc, out) = runCommand(path, "--version", dir);
    EXPECT_EQ(rc, 0) << out;
    EXPECT_EQ(out, name + " " + LCMLOC_VERSION + "\n");
    std::tie(rc, out) = runCommand(path, "--no-such-option", dir);
    EXPECT_EQ(rc, 2) << out;  // a usage error
  }
  fs::remove_all(dir);
}

TEST(CommandLine, OutputIsSpelledOutputEverywhere) {
  const fs::path dir = tempDir("spelling");
  for (const auto& [name, path] : programs()) {
    SCOPED_TRACE(name);
    const auto [rc, out] = runCommand(path, "--help", dir);
    ASSERT_EQ(rc, 0) << out;
    EXPECT_EQ(out.find("--out "), std::string::npos) << out;
    EXPECT_EQ(out.find("--out,"), std::string::npos) << out;
  }
  fs::remove_all(dir);
}

TEST(CommandLine, SubcommandHelpStatesTheExitCodes) {
  const fs::path dir = tempDir("sub");
  for (const auto& [name, args] : std::vector<std::pair<std::string, std::string>>{
           {"lcmloc-log", "cut --help"}, {"lcmloc-log", "to-csv --help"}, {"lcmloc-ctl", "reset --help"}}) {
    const auto [rc, out] = runCommand(program(name), args, dir);
    EXPECT_EQ(rc, 0) << out;
    EXPECT_NE(out.find(kFooter), std::string::npos) << name << " " << args << ": " << out;
  }
  fs::remove_all(dir);
}

TEST(CommandLine, AMissingInputFileIsAUsageError) {
  const fs::path dir = tempDir("missing");
  const std::string missing = (dir / "missing.lcmlog").string();
  for (const auto& [name, args] : std::vector<std::pair<std::string, std::string>>{
           {"lcmloc-replay", missing + " -o " + (dir / "o.lcmlog").string()},
           {"lcmloc-evaluate", missing + " -o " + (dir / "e").string()},
           {"lcmloc-log", "info " + missing},
           {"lcmloc-landmark-experiment", "--log " + missing + " -o " + (dir / "l").string()},
           {"lcmloc-import-vp", "--odometry " + missing + " --gps " + missing + " -o " + (dir / "v").string()}}) {
    const auto [rc, out] = runCommand(program(name), args, dir);
    EXPECT_EQ(rc, 2) << name << ": " << out;
    EXPECT_FALSE(fs::exists(dir / "o.lcmlog")) << name;
  }
  fs::remove_all(dir);
}

// --- no output replaced without --overwrite ---------------------------------------------------

struct WriteCase {
  std::string program;
  std::string args;  ///< {out} is the output path, {in} the imported example, {est} its replay
  bool directory;    ///< the output is a directory
  std::string needs; ///< a data directory the case needs ("" = none)
};

std::ostream& operator<<(std::ostream& os, const WriteCase& c) { return os << c.program << " " << c.args; }

class OverwriteTest : public ::testing::TestWithParam<WriteCase> {
 protected:
  static void SetUpTestSuite() {
    base_ = tempDir("overwrite");
    // Inputs: the documented CSV example imported, and its replay.
    auto [rc, out] = runCommand(program("lcmloc-import"), std::string(LCMLOC_EXAMPLE_DIR) + " -o " + in(), base_);
    ASSERT_EQ(rc, 0) << out;
    std::tie(rc, out) = runCommand(program("lcmloc-replay"), in() + "/run.lcmlog --config " + in() +
                                                                 "/config.yaml --with-inputs --progress 0 -o " + est(),
                                   base_);
    ASSERT_EQ(rc, 0) << out;
  }
  static void TearDownTestSuite() { fs::remove_all(base_); }
  static std::string in() { return (base_ / "in").string(); }
  static std::string est() { return (base_ / "estimates.lcmlog").string(); }

  static std::string expand(std::string s, const std::string& out) {
    for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
             {"{out}", out}, {"{in}", in()}, {"{est}", est()}, {"{vp}", LCMLOC_VP_DIR},
             {"{grid}", LCMLOC_MAGNET_GRID_DIR}}) {
      for (std::size_t at; (at = s.find(key)) != std::string::npos;) s.replace(at, key.size(), value);
    }
    return s;
  }
  static inline fs::path base_;
};

TEST_P(OverwriteTest, RefusesAnExistingOutputWithoutOverwriteAndReplacesItWithIt) {
  const WriteCase& c = GetParam();
  if (!c.needs.empty() && !fs::exists(expand(c.needs, "")))
    GTEST_SKIP() << expand(c.needs, "") << " is not here";
  const fs::path dir = base_ / (c.program + "_" + std::to_string(std::hash<std::string>()(c.args)));
  fs::create_directories(dir);
  const fs::path out = dir / "output";
  const fs::path old = c.directory ? out / "old.txt" : out;
  if (c.directory) fs::create_directories(out);
  std::ofstream(old) << "an earlier output\n";
  const std::string args = expand(c.args, out.string());

  auto [rc, text] = runCommand(program(c.program), args, dir);
  EXPECT_EQ(rc, 2) << text;
  EXPECT_NE(text.find("--overwrite"), std::string::npos) << text;  // the message names the way out
  EXPECT_EQ(readFile(old), "an earlier output\n");
  if (c.directory) EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 1) << text;

  std::tie(rc, text) = runCommand(program(c.program), args + " --overwrite", dir);
  EXPECT_EQ(rc, 0) << text;
  if (c.directory) {
    EXPECT_GT(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 1) << text;
  } else {
    EXPECT_NE(readFile(out), "an earlier output\n") << text;
    EXPECT_GT(fs::file_size(out), 0u) << text;
  }
}

INSTANTIATE_TEST_SUITE_P(
    EveryWriter, OverwriteTest,
    ::testing::Values(
        WriteCase{"lcmloc-import", LCMLOC_EXAMPLE_DIR " -o {out}", true, ""},
        WriteCase{"lcmloc-replay", "{in}/run.lcmlog --config {in}/config.yaml --progress 0 -o {out}", false, ""},
        WriteCase{"lcmloc-evaluate", "{est} --no-plots -o {out}", true, ""},
        WriteCase{"lcmloc-evaluate", "{est} --export-only --tum-dir {out}", true, ""},
        WriteCase{"lcmloc-log", "to-csv {est} -c POSE -o {out}", false, ""},
        WriteCase{"lcmloc-log", "cut {est} --to 1 -o {out}", false, ""},
        WriteCase{"lcmloc-montecarlo", "--runs 1 -o {out}", false, ""},
        WriteCase{"lcmloc-gps-experiment", "--filters dead_reckoning --runs 2 -o {out}", true, ""},
        WriteCase{"lcmloc-ins-experiment", "--starts hard --duration 20 -o {out}", true, ""},
        WriteCase{"lcmloc-landmark-experiment", "--runs 20 -o {out}", true, ""},
        WriteCase{"lcmloc-magnet-grid", "--data {grid} --run line1magnet --import-only -o {out}", true, "{grid}"},
        WriteCase{"lcmloc-import-vp", "--dir {vp} --max-rows 300 -o {out}", false, "{vp}"},
        WriteCase{"lcmloc-vp-experiment", "--dir {vp} --max-rows 300 --filters dead_reckoning -o {out}", true,
                  "{vp}"}));

TEST(CommandLine, InsExperimentRefusesAnExistingSensorLogWithoutOverwrite) {
  const fs::path dir = tempDir("ins_log");
  const fs::path log = dir / "sensors.lcmlog";
  std::ofstream(log) << "an earlier log\n";
  const std::string args = "--starts hard --duration 20 -o " + (dir / "r").string() + " --log " + log.string();
  auto [rc, out] = runCommand(program("lcmloc-ins-experiment"), args, dir);
  EXPECT_EQ(rc, 2) << out;
  EXPECT_EQ(readFile(log), "an earlier log\n");
  EXPECT_FALSE(fs::exists(dir / "r")) << "refused before anything was written";
  std::tie(rc, out) = runCommand(program("lcmloc-ins-experiment"), args + " --overwrite", dir);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(readFile(log), "an earlier log\n");
  fs::remove_all(dir);
}
