// Every command shown in README.md and docs/*.md, read from the files themselves when the test
// runs: a fenced block tagged `sh` is run, command by command, in a scratch directory that holds
// the checkout's build, config, docs, tests and tools (each command must exit 0); a block tagged
// `sh no-run` is checked only: each command names a program that exists, and each option it uses
// appears in that program's --help (for a script: in the script). A command line outside a shell
// block fails. So a documented program or option that stops existing fails here.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "doc_commands.hpp"

namespace fs = std::filesystem;
using namespace doccmd;

namespace {

std::string readFile(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

/// Runs a shell script text in dir; (exit code or -1; output).
std::pair<int, std::string> runIn(const fs::path& dir, const std::string& script, const fs::path& scratch_root) {
  static int n = 0;
  const fs::path file = scratch_root / ("cmd" + std::to_string(++n) + ".sh");
  const fs::path out = scratch_root / ("cmd" + std::to_string(n) + ".out");
  std::ofstream(file) << "set -o pipefail\nexport PATH=" << quote(LCMLOC_BIN_DIR) << ":\"$PATH\"\n"
                      << "export LCM_DEFAULT_URL=memq://\ncd " << quote(dir.string()) << " || exit 99\n"
                      << script << "\n";
  const int st = std::system(("timeout 120 bash " + quote(file.string()) + " > " + quote(out.string()) + " 2>&1").c_str());
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, readFile(out)};
}

std::vector<std::string> docFiles() {
  std::vector<std::string> files{"README.md"};
  std::vector<std::string> docs;
  for (const auto& e : fs::directory_iterator(fs::path(LCMLOC_SOURCE_DIR) / "docs"))
    if (e.path().extension() == ".md") docs.push_back("docs/" + e.path().filename().string());
  std::sort(docs.begin(), docs.end());
  files.insert(files.end(), docs.begin(), docs.end());
  return files;
}

const std::set<std::string> kShellBuiltins{"export", "cd", "cat", "kill", "wait", "echo", "mkdir", "rm",
                                           "cp", "mv", "ls", "sleep", "test", "true", "false", "set",
                                           "source", ".", "diff", "cmp", "head", "tail", "time"};

class Checker {
 public:
  explicit Checker(std::string where) : where_(std::move(where)) {}

  /// Checks one simple command: its program exists; the options used are in its --help.
  void check(const std::vector<std::string>& sc, int line) {
    const std::string at = where_ + ":" + std::to_string(line) + ": ";
    const std::string& prog = sc[0];
    if (kShellBuiltins.count(prog)) return;
    const std::string base = fs::path(prog).filename().string();
    std::string help;
    if (base.rfind("lcmloc-", 0) == 0) {
      const fs::path exe = fs::path(LCMLOC_BIN_DIR) / base;
      if (!fs::exists(exe)) {
        ADD_FAILURE() << at << "`" << prog << "`: no program " << base << " in the build (" << exe << ")";
        return;
      }
      help = helpOf(exe.string(), "");
      if (help.empty()) ADD_FAILURE() << at << base << " --help did not exit 0";
      if (sc.size() > 1 && !sc[1].empty() && std::islower(static_cast<unsigned char>(sc[1][0])) &&
          sc[1].find_first_not_of("abcdefghijklmnopqrstuvwxyz-") == std::string::npos)
        help += helpOf(exe.string(), sc[1]);  // a subcommand's own options
    } else if (prog.rfind("build/", 0) == 0) {  // another program of the build (a benchmark)
      const fs::path exe = fs::path(LCMLOC_BUILD_DIR) / prog.substr(6);
      if (!fs::is_regular_file(exe) || ::access(exe.c_str(), X_OK) != 0) {
        ADD_FAILURE() << at << "`" << prog << "`: no program " << exe << " in the build";
        return;
      }
      help = helpOf(exe.string(), "");
      if (help.empty()) ADD_FAILURE() << at << prog << " --help did not exit 0";
    } else if (prog.find('/') != std::string::npos) {
      const fs::path script = fs::path(LCMLOC_SOURCE_DIR) / prog;
      if (!fs::is_regular_file(script) || ::access(script.c_str(), X_OK) != 0) {
        ADD_FAILURE() << at << "`" << prog << "`: no executable file " << script;
        return;
      }
      help = readFile(script);  // a script's options are spelled in it
    } else {
      if (std::system(("command -v " + quote(prog) + " > /dev/null 2>&1").c_str()) != 0)
        ADD_FAILURE() << at << "`" << prog << "`: not a program on PATH";
      return;  // another project's program: its options are its own
    }
    for (const auto& opt : options(sc))
      EXPECT_TRUE(helpNames(help, opt)) << at << "`" << prog << "` has no option " << opt
                                        << " (not in its --help)";
  }

 private:
  std::string helpOf(const std::string& exe, const std::string& sub) {
    const std::string key = exe + " " + sub;
    auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    const std::string cmd = quote(exe) + (sub.empty() ? "" : " " + quote(sub)) + " --help 2>&1";
    std::string text;
    if (FILE* p = ::popen(cmd.c_str(), "r")) {
      char buf[4096];
      std::size_t n;
      while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) text.append(buf, n);
      const int st = ::pclose(p);
      if (!(WIFEXITED(st) && WEXITSTATUS(st) == 0)) text.clear();
    }
    return cache_[key] = text;
  }

  std::string where_;
  static inline std::map<std::string, std::string> cache_;
};

/// A line of a block that is not a shell block reads as a command: it starts with a program of
/// ours and holds nothing but ASCII outside its comment (a diagram's arrows or an output's units
/// are not commands).
bool looksLikeACommand(const std::string& line) {
  const auto ws = words(line);
  if (ws.empty()) return false;
  for (const auto& w : ws)
    for (char c : w)
      if (static_cast<unsigned char>(c) >= 0x80) return false;
  const std::string& w = ws[0];
  return w.rfind("build/bin/", 0) == 0 || w.rfind("lcmloc-", 0) == 0 || w.rfind("tools/", 0) == 0;
}

}  // namespace

// --- the reading of the docs itself -------------------------------------------------------

TEST(DocCommandParser, FindsBlocksTheirTagsAndCommands) {
  const std::string md =
      "text\n```sh\nbuild/bin/lcmloc-log info a.lcmlog   # a comment\n\n# only a comment\n"
      "build/bin/lcmloc-replay a.lcmlog \\\n    --with-inputs -o b.lcmlog\n```\n"
      "  ```sh no-run\n  lcmloc-ctl reset\n  ```\n~~~\nplain\n~~~\n```yaml\nfusion: {}\n```\n";
  const auto blocks = fencedBlocks(md);
  ASSERT_EQ(blocks.size(), 4u);
  EXPECT_TRUE(isRun(blocks[0]));
  EXPECT_TRUE(isShell(blocks[1]));
  EXPECT_FALSE(isRun(blocks[1]));
  EXPECT_FALSE(isShell(blocks[2]));
  EXPECT_FALSE(isShell(blocks[3]));
  const auto cmds = commands(blocks[0]);
  ASSERT_EQ(cmds.size(), 2u);
  EXPECT_EQ(cmds[0].line, 3);
  EXPECT_EQ(cmds[1].line, 6);
  const auto w = words(cmds[1].text);
  EXPECT_EQ(w, (std::vector<std::string>{"build/bin/lcmloc-replay", "a.lcmlog", "--with-inputs", "-o", "b.lcmlog"}));
  EXPECT_EQ(words(cmds[0].text).size(), 3u);  // the comment is not a word
  EXPECT_EQ(commands(blocks[1]).size(), 1u);
}

TEST(DocCommandParser, SplitsOperatorsDropsAssignmentsRedirectionsAndHereDocuments) {
  const auto sc = simpleCommands(words("A=1 lcmloc-logger -o 'x y.lcmlog' & lcm-logplayer -e '^(A|B)$' l > o 2>&1; kill %1"));
  ASSERT_EQ(sc.size(), 3u);
  EXPECT_EQ(sc[0], (std::vector<std::string>{"lcmloc-logger", "-o", "x y.lcmlog"}));
  EXPECT_EQ(sc[1], (std::vector<std::string>{"lcm-logplayer", "-e", "^(A|B)$", "l"}));
  EXPECT_EQ(sc[2], (std::vector<std::string>{"kill", "%1"}));
  Block b;
  b.line = 1;
  b.lines = {"cat > /tmp/f.yaml <<'EOF'", "scenario: {realtime_factor: 10}", "EOF", "lcmloc-launcher --config /tmp/f.yaml"};
  b.line_numbers = {2, 3, 4, 5};
  const auto cmds = commands(b);
  ASSERT_EQ(cmds.size(), 2u);
  EXPECT_EQ(simpleCommands(words(cmds[0].text)), (std::vector<std::vector<std::string>>{{"cat"}}));
  EXPECT_EQ(cmds[1].line, 5);
}

TEST(DocCommandParser, TellsACommandLineFromADiagramOrAnOutput) {
  EXPECT_TRUE(looksLikeACommand("build/bin/lcmloc-log info run.lcmlog"));
  EXPECT_TRUE(looksLikeACommand("lcmloc-replay run.lcmlog -o out.lcmlog   # \u00a7 2"));
  EXPECT_TRUE(looksLikeACommand("tools/spy.sh"));
  EXPECT_FALSE(looksLikeACommand(" lcmloc-sim \u2500\u2500GROUND_TRUTH\u2500\u2500\u252c\u2500> lcmloc-odometry"));
  EXPECT_FALSE(looksLikeACommand("log:        ref.lcmlog (13657 bytes)"));
  EXPECT_FALSE(looksLikeACommand("$ lcmloc-fusion --config bad.yaml"));
}

TEST(DocCommandParser, OptionsAndTheirMentionInAHelpText) {
  EXPECT_EQ(options({"lcmloc-evaluate", "LOG", "[--all-poses]", "[-o", "DIR]", "[--tum-dir", "D", "[--export-only]]",
                     "--confidence=0.9", "-1.5", "..."}),
            (std::vector<std::string>{"--all-poses", "-o", "--tum-dir", "--export-only", "--confidence"}));
  const std::string help = "  -o,--output TEXT   where\n  --all-poses        every POSE_*\n";
  EXPECT_TRUE(helpNames(help, "-o"));
  EXPECT_TRUE(helpNames(help, "--output"));
  EXPECT_TRUE(helpNames(help, "--all-poses"));
  EXPECT_FALSE(helpNames(help, "--all"));   // a prefix of another option is not it
  EXPECT_FALSE(helpNames(help, "--poses"));  // nor is its tail
  EXPECT_FALSE(helpNames(help, "--out"));
}

// --- the docs ---------------------------------------------------------------------------------

class DocCommands : public ::testing::TestWithParam<std::string> {};

TEST_P(DocCommands, ExistAndRun) {
  const std::string rel = GetParam();
  const std::string text = readFile(fs::path(LCMLOC_SOURCE_DIR) / rel);
  ASSERT_FALSE(text.empty()) << rel;
  Checker checker(rel);
  fs::path root, scratch;
  int ran = 0;
  for (const auto& b : fencedBlocks(text)) {
    if (!isShell(b)) {
      for (std::size_t i = 0; i < b.lines.size(); ++i)
        EXPECT_FALSE(looksLikeACommand(b.lines[i]))
            << rel << ":" << b.line_numbers[i] << ": a command outside a shell block: tag the block `sh` "
            << "(run by this test) or `sh no-run` (checked only): " << b.lines[i];
      continue;
    }
    for (const auto& c : commands(b)) {
      for (const auto& sc : simpleCommands(words(c.text))) checker.check(sc, c.line);
      if (!isRun(b)) continue;
      if (root.empty()) {  // a scratch copy of the checkout's layout, outputs in its own out/
        std::string stem = rel;
        std::replace_if(stem.begin(), stem.end(), [](char ch) { return !std::isalnum(static_cast<unsigned char>(ch)); }, '_');
        root = fs::temp_directory_path() / ("lcmloc_doc_" + stem + "_" + std::to_string(::getpid()));
        fs::remove_all(root);
        scratch = root / "checkout";
        fs::create_directories(scratch);
        fs::create_directory_symlink(LCMLOC_BUILD_DIR, scratch / "build");
        for (const char* d : {"config", "docs", "tests", "tools", "lcmtypes"})
          fs::create_directory_symlink(fs::path(LCMLOC_SOURCE_DIR) / d, scratch / d);
      }
      ++ran;
      const auto [code, out] = runIn(scratch, c.text, root);
      EXPECT_EQ(code, 0) << rel << ":" << c.line << ": `" << c.text << "` exited " << code << ":\n"
                         << (out.size() > 3000 ? "..." + out.substr(out.size() - 3000) : out);
    }
  }
  if (!root.empty()) fs::remove_all(root);  // a failure message holds the command's output
  RecordProperty("commands_run", ran);
}

INSTANTIATE_TEST_SUITE_P(Docs, DocCommands, ::testing::ValuesIn(docFiles()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string n = info.param;
                           std::replace_if(n.begin(), n.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); }, '_');
                           return n;
                         });

TEST(DocCommandsAll, TheReadmeRunsCommandsAndTheDocsShowMany) {
  int run_blocks = 0, shell_blocks = 0;
  for (const auto& rel : docFiles())
    for (const auto& b : fencedBlocks(readFile(fs::path(LCMLOC_SOURCE_DIR) / rel))) {
      shell_blocks += isShell(b);
      run_blocks += isRun(b) && rel == "README.md";
    }
  EXPECT_GE(run_blocks, 2);     // the README's own-data walk-through and the offline replay
  EXPECT_GE(shell_blocks, 20);  // a parser that finds nothing would pass every file
}
