// lcmloc-log (info, to-csv, cut) on logs the tests write with lcm::LogFile (the writer
// lcm-logger uses) and with our EventFile; damaged logs; the file-name pattern.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <lcm/lcm_coretypes.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/logio/event_file.hpp"
#include "lcmloc/logio/log_writer.hpp"
#include "lcmloc/logtool/command.hpp"
#include "lcmloc/logtool/log_tool.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/wire.hpp"

namespace fs = std::filesystem;

namespace {

constexpr int64_t kT0 = 1700000000000000;  // log time of the first event [us]

struct ToolRun {
  int rc = -1;
  std::string out, err;
};

std::string slurp(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> v;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

std::vector<std::string> words(const std::string& line) {
  std::vector<std::string> v;
  std::istringstream in(line);
  for (std::string w; in >> w;) v.push_back(w);
  return v;
}

template <class Msg>
std::vector<uint8_t> enc(const Msg& m) {
  std::vector<uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

/// An odometry message with seq and utime t.
std::vector<uint8_t> odometry(int64_t seq, int64_t t) {
  lcmloc::odometry_t o{};
  o.utime = t;
  o.seq = seq;
  return enc(o);
}

/// Every regular file under dir, recursively.
std::set<fs::path> filesUnder(const fs::path& dir) {
  std::set<fs::path> v;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) v.insert(e.path());
  return v;
}

class LogTools : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("lcmloc_logtools_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  std::string path(const std::string& n) const { return (dir_ / n).string(); }

  ToolRun tool(const std::string& args) const {
    const std::string o = path("tool.out"), e = path("tool.err");
    ToolRun r;
    const int st = std::system((std::string(LCMLOC_LOG_BIN) + " " + args + " >" + o + " 2>" + e).c_str());
    r.rc = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    r.out = slurp(o);
    r.err = slurp(e);
    return r;
  }

  /// Appends one event (channel, log time, payload) with LCM's writer.
  static void writeEvent(lcm::LogFile& log, const std::string& ch, int64_t t, const std::vector<uint8_t>& data) {
    lcm::LogEvent ev;
    ev.eventnum = 0;
    ev.timestamp = t;
    ev.channel = ch;
    ev.datalen = static_cast<int32_t>(data.size());
    ev.data = const_cast<uint8_t*>(data.data());
    ASSERT_EQ(log.writeEvent(&ev), 0);
  }

  /// The reference log: ODOMETRY at 100 Hz with seq 50 missing, POSE (arrays), HEARTBEAT from
  /// two processes, RAW of an unknown type, one undecodable ODOMETRY_BAD event.
  /// Returns the byte offset of every event.
  std::vector<int64_t> writeReference(const std::string& file) {
    std::vector<int64_t> starts;
    lcm::LogFile log(file, "w");
    EXPECT_TRUE(log.good());
    auto put = [&](const std::string& ch, int64_t t, const std::vector<uint8_t>& data) {
      starts.push_back(ftello(log.getFilePtr()));
      writeEvent(log, ch, t, data);
    };
    for (int i = 0; i < 100; ++i) {
      const int64_t t = kT0 + i * 10000;
      if (i != 50) {
        lcmloc::odometry_t o{};
        o.utime = t;
        o.seq = i;
        o.delta_s = 0.25 * i;
        o.ticks = i;
        o.has_steering = true;
        put("ODOMETRY", t, enc(o));
      }
      if (i % 10 == 0) {
        lcmloc::pose_t p{};
        p.utime = t;
        p.seq = i / 10;
        p.filter = "ukf, v2";  // a comma: quoted in CSV
        p.dim = 3;
        p.state = {1.0 * i, 2.0, 0.5};
        p.state_names = {"x", "y", "theta"};
        p.covariance = {{1, 0, 0}, {0, 2, 0}, {0, 0, 3}};
        put("POSE", t, enc(p));
        for (const char* proc : {"sim", "fusion"}) {
          lcmloc::heartbeat_t h{};
          h.utime = t;
          h.seq = i / 10;
          h.process = proc;
          h.state = "running";
          h.counter_names = {"published"};
          h.counters = {i};
          h.num_counters = 1;
          put("HEARTBEAT", t, enc(h));
        }
      }
      if (i % 20 == 0) put("RAW", t, {1, 2, 3, 4, 5, 6, 7, 8, 9});
    }
    auto bad = enc(lcmloc::odometry_t{});
    bad.resize(20);  // the fingerprint of odometry_t, then too few bytes
    put("ODOMETRY_BAD", kT0 + 995000, bad);
    return starts;
  }

  fs::path dir_;
};

/// The row of channel ch in info's table, split on whitespace.
std::vector<std::string> row(const std::string& out, const std::string& ch) {
  for (const auto& l : lines(out)) {
    auto w = words(l);
    if (!w.empty() && w[0] == ch) return w;
  }
  return {};
}

}  // namespace

// The big-endian helpers write what LCM's own encoder writes (lcm_coretypes.h) and read it back.
TEST(Wire, StoresAndLoadsIntegersAsLcmEncodesThem) {
  const int64_t i64 = -0x0123456789abcdefLL;
  const int32_t i32 = -0x12345678;
  uint8_t lcm64[8], lcm32[4], ours64[8], ours32[4];
  ASSERT_EQ(__int64_t_encode_array(lcm64, 0, 8, &i64, 1), 8);
  ASSERT_EQ(__int32_t_encode_array(lcm32, 0, 4, &i32, 1), 4);
  lcmloc::wire::storeBig64(ours64, static_cast<uint64_t>(i64));
  lcmloc::wire::storeBig32(ours32, static_cast<uint32_t>(i32));
  EXPECT_EQ(0, std::memcmp(lcm64, ours64, 8));
  EXPECT_EQ(0, std::memcmp(lcm32, ours32, 4));
  EXPECT_EQ(static_cast<int64_t>(lcmloc::wire::loadBig64(lcm64)), i64);
  EXPECT_EQ(static_cast<int64_t>(lcmloc::wire::loadBig(lcm64, 8)), i64);
  EXPECT_EQ(static_cast<int32_t>(lcmloc::wire::loadBig(lcm32, 4)), i32);
  EXPECT_EQ(lcmloc::wire::loadBig(lcm64 + 6, 2), static_cast<uint64_t>(lcm64[6]) << 8 | lcm64[7]);
}

TEST_F(LogTools, InfoListsChannelsTypesCountsRatesGapsAndUndecodable) {
  const std::string log = path("ref.lcmlog");
  writeReference(log);
  const ToolRun r = tool("info " + log);
  ASSERT_EQ(r.rc, 0) << r.out << r.err;
  // columns: channel type count rate bytes seq_gaps undecodable
  auto odo = row(r.out, "ODOMETRY");
  ASSERT_EQ(odo.size(), 7u) << r.out;
  EXPECT_EQ(odo[1], "lcmloc.odometry_t");
  EXPECT_EQ(odo[2], "99");
  EXPECT_NEAR(std::stod(odo[3]), 98 / 0.99, 0.01);  // 99 events over 0.99 s
  EXPECT_EQ(odo[5], "1") << "seq 50 is missing";
  EXPECT_EQ(odo[6], "0");
  auto hb = row(r.out, "HEARTBEAT");
  ASSERT_EQ(hb.size(), 7u) << r.out;
  EXPECT_EQ(hb[2], "20");
  EXPECT_EQ(hb[5], "0") << "two publishers, each in order: no gaps";
  auto raw = row(r.out, "RAW");
  ASSERT_GE(raw.size(), 3u);
  EXPECT_EQ(raw[1], "unknown");
  EXPECT_EQ(raw[2], "0x0102030405060708");
  auto bad = row(r.out, "ODOMETRY_BAD");
  ASSERT_EQ(bad.size(), 7u) << r.out;
  EXPECT_EQ(bad[6], "1");
  EXPECT_NE(r.out.find("events:     135 on 5 channels"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(0.995 s)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("undecodable ODOMETRY_BAD event at byte"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("DAMAGE"), std::string::npos) << r.out;
}

TEST_F(LogTools, ToCsvOneChannelHeaderNamedAfterFieldsArraysExpanded) {
  const std::string log = path("ref.lcmlog");
  writeReference(log);
  ToolRun r = tool("to-csv " + log + " --channel ODOMETRY");
  ASSERT_EQ(r.rc, 0) << r.err;
  auto l = lines(r.out);
  ASSERT_EQ(l.size(), 100u);  // header + 99 rows
  EXPECT_EQ(l[0], "log_utime,utime,seq,delta_s,ticks,steering,has_steering,delta_theta");
  EXPECT_EQ(l[1], std::to_string(kT0) + "," + std::to_string(kT0) + ",0,0,0,0,1,0");
  EXPECT_EQ(l[51], std::to_string(kT0 + 510000) + "," + std::to_string(kT0 + 510000) + ",51,12.75,51,0,1,0");

  r = tool("to-csv " + log + " --channel POSE -o " + path("pose.csv"));
  ASSERT_EQ(r.rc, 0) << r.err;
  l = lines(slurp(path("pose.csv")));
  ASSERT_EQ(l.size(), 11u);
  EXPECT_EQ(l[0], "log_utime,utime,seq,filter,status,dim,state_0,state_1,state_2,state_names_0,state_names_1,"
                  "state_names_2,covariance_0_0,covariance_0_1,covariance_0_2,covariance_1_0,covariance_1_1,"
                  "covariance_1_2,covariance_2_0,covariance_2_1,covariance_2_2");
  EXPECT_EQ(l[2], std::to_string(kT0 + 100000) + "," + std::to_string(kT0 + 100000) +
                      ",1,\"ukf, v2\",0,3,10,2,0.5,x,y,theta,1,0,0,0,2,0,0,0,3");

  // -c before the log: one regex per -c (the log path used to be taken as a second regex,
  // "log is required")
  r = tool("to-csv -c POSE " + log + " -o " + path("pose2.csv"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(slurp(path("pose2.csv")), slurp(path("pose.csv")));
  r = tool("cut -c POSE " + log + " -o " + path("pose.lcmlog"));
  EXPECT_EQ(r.rc, 0) << r.err;
}

TEST_F(LogTools, ToCsvAllChannelsWritesOneFilePerDecodableChannel) {
  const std::string log = path("ref.lcmlog");
  writeReference(log);
  const ToolRun r = tool("to-csv " + log + " -o " + path("csv"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("csv/ODOMETRY.csv")));
  EXPECT_TRUE(fs::exists(path("csv/POSE.csv")));
  EXPECT_FALSE(fs::exists(path("csv/RAW.csv"))) << "unknown type: not exported";
  EXPECT_NE(r.err.find("RAW: 5 event(s) of a type this tool does not know"), std::string::npos) << r.err;
  auto hb = lines(slurp(path("csv/HEARTBEAT.csv")));
  ASSERT_EQ(hb.size(), 21u);
  EXPECT_EQ(hb[0], "log_utime,utime,seq,process,pid,state,num_counters,counter_published");
  // Several channels and no directory: a clear error.
  const ToolRun bad = tool("to-csv " + log);
  EXPECT_EQ(bad.rc, 1);
  EXPECT_NE(bad.err.find("give --output DIR"), std::string::npos) << bad.err;
}

TEST_F(LogTools, ToCsvChannelNamesNeverWriteOutsideTheDirectory) {
  // Channel names are whatever a publisher sent: "../x" and an absolute path used to become
  // DIR/../x.csv and /abs/x.csv.
  const std::string log = path("traversal.lcmlog"), out = path("out/csv");
  const std::string abs = path("escape_abs");  // an absolute channel name
  {
    lcmloc::logger::EventFile f(log);
    const std::vector<std::string> chans{"../escape_rel", abs, "..", "ODOMETRY"};
    for (int i = 0; i < 20; ++i) {
      const auto& ch = chans[static_cast<std::size_t>(std::min(i, 3))];
      const auto d = odometry(i, kT0 + i * 10000);
      ASSERT_EQ(f.append(kT0 + i * 10000, ch, d.data(), d.size()), 0);
    }
    ASSERT_EQ(f.close(), 0);
  }
  const ToolRun r = tool("to-csv " + log + " -o " + out);
  ASSERT_EQ(r.rc, 0) << r.err;
  std::set<fs::path> written;
  for (const auto& p : filesUnder(dir_))
    if (p.parent_path() == dir_ && (p.filename() == "traversal.lcmlog" || p.filename().string().rfind("tool.", 0) == 0))
      continue;  // the log and the captured output
    else
      written.insert(p);
  EXPECT_EQ(written.size(), 4u);
  int64_t rows = 0;
  for (const auto& p : written) {
    EXPECT_EQ(p.parent_path(), fs::path(out)) << p << " is outside " << out;
    const auto l = lines(slurp(p.string()));
    ASSERT_FALSE(l.empty()) << p;
    EXPECT_EQ(l[0].rfind("log_utime,utime,seq,", 0), 0u) << p;
    rows += static_cast<int64_t>(l.size()) - 1;
  }
  EXPECT_EQ(rows, 20) << "every row of every channel in some file";
  EXPECT_EQ(lines(slurp(out + "/ODOMETRY.csv")).size(), 18u) << "a plain channel name keeps CHANNEL.csv";
  EXPECT_TRUE(fs::exists(out + "/___escape_rel.csv"));
  EXPECT_NE(r.err.find("../escape_rel: 1 rows, 8 columns -> " + out + "/___escape_rel.csv"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("out/escape_rel.csv")));
  EXPECT_FALSE(fs::exists(abs + ".csv"));
}

TEST_F(LogTools, ToCsvChannelsWhoseFileNamesCollideGetDistinctFiles) {
  // ODOMETRY and ./ODOMETRY used to open the same file: half of the rows lost, exit 0.
  // channel -> file: plain names keep theirs, the others a free sanitized name
  const std::map<std::string, std::string> expected{
      {"ODOMETRY", "ODOMETRY.csv"}, {"./ODOMETRY", "__ODOMETRY.csv"}, {"a_b", "a_b.csv"},
      {"a/b", "a_b_2.csv"}, {"a:b", "a_b_3.csv"}};
  for (const std::vector<std::string>& chans : {std::vector<std::string>{"ODOMETRY", "./ODOMETRY"},
                                               std::vector<std::string>{"ODOMETRY", "./ODOMETRY", "a_b", "a/b", "a:b"}}) {
    const std::string log = path("alias.lcmlog"), out = path("csv" + std::to_string(chans.size()));
    {
      lcmloc::logger::EventFile f(log);
      for (std::size_t i = 0; i < 10 * chans.size(); ++i) {
        const auto d = odometry(static_cast<int64_t>(i), kT0 + static_cast<int64_t>(i) * 10000);
        ASSERT_EQ(f.append(kT0 + static_cast<int64_t>(i) * 10000, chans[i % chans.size()], d.data(), d.size()), 0);
      }
      ASSERT_EQ(f.close(), 0);
    }
    const ToolRun r = tool("to-csv " + log + " -o " + out);
    EXPECT_EQ(r.rc, 0) << r.err;
    EXPECT_EQ(filesUnder(out).size(), chans.size());
    for (std::size_t c = 0; c < chans.size(); ++c) {
      const std::string file = out + "/" + expected.at(chans[c]);
      EXPECT_NE(r.err.find(chans[c] + ": 10 rows, 8 columns -> " + file), std::string::npos) << r.err;
      const auto l = lines(slurp(file));
      ASSERT_EQ(l.size(), 11u) << file;
      for (std::size_t k = 1; k < l.size(); ++k) {  // the rows of this channel: c, c + n, c + 2n, ...
        const auto i = static_cast<int64_t>(c + chans.size() * (k - 1));
        EXPECT_EQ(l[k].rfind(std::to_string(kT0 + i * 10000) + ",", 0), 0u) << file << ": " << l[k];
      }
    }
  }
}

TEST_F(LogTools, ToCsvColumnsAreTheUnionInMessageOrderAndAHugeArrayIsRefused) {
  const std::string log = path("wide.lcmlog");
  auto ruler = [](int64_t seq, int n) {
    lcmloc::magruler_t m{};
    m.seq = seq;
    m.num_sensors = n;
    m.readings.assign(static_cast<std::size_t>(n), 0.5);
    return enc(m);
  };
  auto write = [&](const std::vector<int>& sizes) {
    lcmloc::logger::EventFile f(log);
    for (std::size_t i = 0; i < sizes.size(); ++i) {
      const auto d = ruler(static_cast<int64_t>(i), sizes[i]);
      ASSERT_EQ(f.append(kT0 + static_cast<int64_t>(i), "MAGRULER", d.data(), d.size()), 0);
    }
    ASSERT_EQ(f.close(), 0);
  };
  // A longer array widens the table in place: readings_2 right after readings_1.
  write({2, 3, 1});
  ToolRun r = tool("to-csv " + log + " -o " + path("m.csv"));
  ASSERT_EQ(r.rc, 0) << r.err;
  auto l = lines(slurp(path("m.csv")));
  ASSERT_EQ(l.size(), 4u);
  EXPECT_EQ(l[0], "log_utime,utime,seq,num_sensors,readings_0,readings_1,readings_2,detected,lateral_offset,quality");
  EXPECT_EQ(l[1], std::to_string(kT0) + ",0,0,2,0.5,0.5,,0,0,0");
  EXPECT_EQ(l[3], std::to_string(kT0 + 2) + ",0,2,1,0.5,,,0,0,0");
  // 9,994 readings (10,000 columns): written; one more: refused, nothing written.
  write({13, 9994, 13});
  r = tool("to-csv " + log + " -o " + path("w.csv"));
  ASSERT_EQ(r.rc, 0) << r.err;
  l = lines(slurp(path("w.csv")));
  ASSERT_EQ(l.size(), 4u);
  EXPECT_EQ(std::count(l[0].begin(), l[0].end(), ','), 10000);
  write({13, 9995, 13});
  r = tool("to-csv " + log + " -o " + path("x.csv"));
  EXPECT_EQ(r.rc, 1) << r.err;
  EXPECT_NE(r.err.find("MAGRULER: more than 10000 columns (widest message: 10001 fields)"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(path("x.csv"))) << "nothing written";
}

TEST_F(LogTools, CutKeepsTheTimeWindowAndChannelsAndLcmReadsTheResult) {
  const std::string log = path("ref.lcmlog");
  writeReference(log);
  const ToolRun r = tool("cut " + log + " -o " + path("cut.lcmlog") + " --from 0.2 --to 0.5 --channel ODOM.*");
  ASSERT_EQ(r.rc, 0) << r.err;
  // lcm::LogFile (what lcm-logplayer uses) reads the new file: events 20..49 of ODOMETRY.
  lcm::LogFile in(path("cut.lcmlog"), "r");
  ASSERT_TRUE(in.good());
  int64_t n = 0;
  while (const lcm::LogEvent* ev = in.readNextEvent()) {
    EXPECT_EQ(ev->channel, "ODOMETRY");
    EXPECT_EQ(ev->eventnum, n);
    lcmloc::odometry_t o;
    ASSERT_GE(o.decode(ev->data, 0, ev->datalen), 0);
    EXPECT_EQ(o.seq, 20 + n);
    EXPECT_EQ(ev->timestamp, kT0 + o.seq * 10000);
    ++n;
  }
  EXPECT_EQ(n, 30);  // seq 20 .. 50 (0.20 .. 0.50 s inclusive), 50 missing
  EXPECT_NE(r.err.find("wrote 30 of 135 events"), std::string::npos) << r.err;

  // Cutting a log onto itself is refused before the file is opened for writing (a bad argument).
  const auto size = fs::file_size(log);
  const ToolRun self = tool("cut " + log + " -o " + log);
  EXPECT_EQ(self.rc, 2) << self.err;
  EXPECT_NE(self.err.find("is the input log"), std::string::npos) << self.err;
  EXPECT_EQ(fs::file_size(log), size);
}

// The subcommands are a library (lcmloc-log's main is their command line): cut called in-process
// keeps a window of log times, refuses an empty window as a bad argument, and says a truncated
// log is damaged while keeping its intact events.
TEST_F(LogTools, CutAsALibraryKeepsTheUtimeWindowAndReportsDamage) {
  const std::string log = path("ref.lcmlog");
  const std::vector<int64_t> starts = writeReference(log);
  lcmloc::logtool::CutOptions o;
  o.channels = {"ODOMETRY"};
  o.from_utime = kT0 + 100000;
  o.to_utime = kT0 + 190000;
  ASSERT_EQ(lcmloc::logtool::cut(log, path("window.lcmlog"), o), lcmloc::app::kExitOk);
  std::vector<int64_t> seqs;
  lcm::LogFile in(path("window.lcmlog"), "r");
  ASSERT_TRUE(in.good());
  while (const lcm::LogEvent* ev = in.readNextEvent()) {
    lcmloc::odometry_t m;
    ASSERT_GE(m.decode(ev->data, 0, ev->datalen), 0);
    seqs.push_back(m.seq);
  }
  ASSERT_EQ(seqs.size(), 10u);
  EXPECT_EQ(seqs.front(), 10);
  EXPECT_EQ(seqs.back(), 19);

  lcmloc::logtool::CutOptions empty;
  empty.from = 0.5;
  empty.to = 0.2;
  EXPECT_THROW(lcmloc::logtool::cut(log, path("empty.lcmlog"), empty), lcmloc::app::ConfigError);

  // Cut short inside the event that starts at starts[40]: everything before it is kept.
  const std::string truncated = path("truncated.lcmlog");
  fs::copy_file(log, truncated);
  fs::resize_file(truncated, static_cast<std::uintmax_t>(starts[40] + 10));
  ASSERT_EQ(lcmloc::logtool::cut(truncated, path("kept.lcmlog"), lcmloc::logtool::CutOptions{}),
            lcmloc::app::kExitInputDamaged);
  lcm::LogFile kept(path("kept.lcmlog"), "r");
  ASSERT_TRUE(kept.good());
  int64_t n = 0;
  while (kept.readNextEvent()) ++n;
  EXPECT_EQ(n, 40);
}

// lcmloc-log's command as a library (its main is the command line): "cut" parsed into a
// LogCommand and run in-process writes the window; an existing output is refused without
// --overwrite and left as it was; a missing log is a bad argument.
TEST_F(LogTools, TheCutCommandRunsInProcessAndRefusesAnExistingOutputWithoutOverwrite) {
  const std::string log = path("ref.lcmlog"), out = path("cut.lcmlog");
  writeReference(log);
  auto count = [](const std::string& file) {
    lcm::LogFile in(file, "r");
    EXPECT_TRUE(in.good());
    int64_t n = 0;
    while (in.good() && in.readNextEvent()) ++n;
    return n;
  };
  lcmloc::logtool::LogCommand c;
  CLI::App app;
  lcmloc::logtool::addLogOptions(app, c);
  app.parse("cut " + log + " -o " + out + " --from 0.2 --to 0.5 -c ODOM.*", false);
  ASSERT_EQ(c.subcommand, lcmloc::logtool::Subcommand::Cut);
  ASSERT_EQ(lcmloc::logtool::runLogCommand(c), lcmloc::app::kExitOk);
  EXPECT_EQ(count(out), 30);  // ODOMETRY seq 20 .. 50, 50 missing

  c.cut = lcmloc::logtool::CutOptions{};  // the whole log
  EXPECT_THROW(lcmloc::logtool::runLogCommand(c), lcmloc::app::UsageError);
  EXPECT_EQ(count(out), 30);
  c.overwrite = true;
  ASSERT_EQ(lcmloc::logtool::runLogCommand(c), lcmloc::app::kExitOk);
  EXPECT_EQ(count(out), 135);

  c.log_path = path("missing.lcmlog");
  EXPECT_THROW(lcmloc::logtool::runLogCommand(c), lcmloc::app::ConfigError);
}

// A CSV on stdout that cannot be written (a full disk behind a redirection, a closed pipe) was
// reported as "N rows" with exit 0.
TEST_F(LogTools, ToCsvOnAStdoutThatCannotBeWrittenFails) {
  const std::string log = path("ref.lcmlog");
  writeReference(log);
  for (const std::string out : {"", " -o -"}) {
    const std::string e = path("full.err");
    const int st = std::system((std::string(LCMLOC_LOG_BIN) + " to-csv " + log + " -c ODOMETRY" + out +
                                " > /dev/full 2>" + e).c_str());
    EXPECT_EQ(WIFEXITED(st) ? WEXITSTATUS(st) : -1, 1) << out;
    const std::string err = slurp(e);
    EXPECT_NE(err.find("writing CSV to stdout failed"), std::string::npos) << err;
    EXPECT_EQ(err.find(" rows, "), std::string::npos) << err;
  }
  const ToolRun ok = tool("to-csv " + log + " -c ODOMETRY");
  EXPECT_EQ(ok.rc, 0) << ok.err;
  // A channel regex that does not compile is a bad argument (exit 2; it was 1).
  for (const std::string& cmd : {"to-csv " + log + " -c '['", "cut " + log + " -o " + path("x.lcmlog") + " -c '('"}) {
    const ToolRun r = tool(cmd);
    EXPECT_EQ(r.rc, 2) << cmd << "\n" << r.err;
    EXPECT_NE(r.err.find("--channel: bad channel regex"), std::string::npos) << r.err;
  }
  // cut with nothing in its window writes an empty log and says so.
  const ToolRun none = tool("cut " + log + " -o " + path("none.lcmlog") + " -c NOPE");
  EXPECT_EQ(none.rc, 0) << none.err;
  EXPECT_NE(none.err.find("none.lcmlog holds no events"), std::string::npos) << none.err;
}

TEST_F(LogTools, ToCsvAndCutNeverWriteOverTheLog) {
  const std::string log = path("ref.lcmlog");
  writeReference(log);
  const std::string before = slurp(log);
  fs::create_symlink(log, path("sym.lcmlog"));
  fs::create_hard_link(log, path("hard.lcmlog"));
  for (const std::string& out : {log, path("sym.lcmlog"), path("hard.lcmlog"), path("./ref.lcmlog")}) {
    for (const std::string& cmd : {"to-csv " + log + " -c ODOMETRY -o " + out, "cut " + log + " -o " + out}) {
      const ToolRun r = tool(cmd);
      EXPECT_EQ(r.rc, 2) << cmd << "\n" << r.err;
      EXPECT_NE(r.err.find("is the input log"), std::string::npos) << cmd << "\n" << r.err;
    }
  }
  // Several channels to a directory in which one CHANNEL.csv is the log itself: refused even with
  // --overwrite (without it, the directory is refused as not empty).
  fs::create_directories(path("d"));
  fs::create_hard_link(log, path("d/POSE.csv"));
  EXPECT_EQ(tool("to-csv " + log + " -o " + path("d")).rc, 2);
  const ToolRun dir = tool("to-csv " + log + " -o " + path("d") + " --overwrite");
  EXPECT_EQ(dir.rc, 2) << dir.err;
  EXPECT_NE(dir.err.find("is the input log"), std::string::npos) << dir.err;
  EXPECT_FALSE(fs::exists(path("d/ODOMETRY.csv"))) << "nothing written";
  EXPECT_EQ(slurp(log), before);
}

TEST_F(LogTools, CutBoundsBeyondTheLogOrNotANumber) {
  const std::string log = path("ref.lcmlog");
  writeReference(log);
  auto kept = [&](const std::string& args) -> int64_t {
    fs::remove(path("cut.lcmlog"));
    const ToolRun r = tool("cut " + log + " -o " + path("cut.lcmlog") + " " + args);
    EXPECT_EQ(r.rc, 0) << args << "\n" << r.err;
    if (r.rc != 0) return -1;
    return lcmloc::logio::scanLog(path("cut.lcmlog"), [](const lcmloc::logio::RawEvent&) {}).events_read;
  };
  // 1e13 s and 1e14 s are beyond int64 microseconds: they used to overflow (keep all / none).
  EXPECT_EQ(kept("--from 1e13"), 0);
  EXPECT_EQ(kept("--to 1e14"), 135);
  EXPECT_EQ(kept("--from 0 --to 1e300"), 135);
  for (const std::string& bad : std::vector<std::string>{"--from nan", "--to nan", "--from 0.5 --to 0.2",
                                 "--from-utime " + std::to_string(kT0 + 2) + " --to-utime " + std::to_string(kT0 + 1)}) {
    const ToolRun r = tool("cut " + log + " -o " + path("bad.lcmlog") + " " + bad);
    EXPECT_EQ(r.rc, 2) << bad << "\n" << r.err;
    EXPECT_FALSE(fs::exists(path("bad.lcmlog"))) << bad;
  }
}

TEST_F(LogTools, LogTimesBeforeTheEpochAndEmptyPayloadsAreShownAsTheyAre) {
  const std::string log = path("odd.lcmlog");
  {
    lcm::LogFile out(log, "w");
    auto put = [&](int64_t t, const std::vector<uint8_t>& data) {
      lcm::LogEvent ev;
      ev.eventnum = 0;
      ev.timestamp = t;
      ev.channel = "ODOMETRY";
      ev.datalen = static_cast<int32_t>(data.size());
      ev.data = const_cast<uint8_t*>(data.data());
      ASSERT_EQ(out.writeEvent(&ev), 0);
    };
    lcmloc::odometry_t o{};
    std::vector<uint8_t> b(static_cast<std::size_t>(o.getEncodedSize()));
    o.encode(b.data(), 0, static_cast<int>(b.size()));
    put(-1, b);   // 1 us before 1970
    put(5, {});   // an empty payload on the same channel
    put(7, b);
  }
  ToolRun r = tool("info " + log);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("time span:  1969-12-31 23:59:59.999999 UTC .. 1970-01-01 00:00:00.000007 UTC"),
            std::string::npos) << r.out;
  auto odo = row(r.out, "ODOMETRY");
  ASSERT_EQ(odo.size(), 7u) << r.out;
  EXPECT_EQ(odo[1], "lcmloc.odometry_t") << "an empty payload is no type of its own";
  EXPECT_EQ(odo[6], "1");
  EXPECT_NE(r.out.find("undecodable ODOMETRY event at byte"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0 bytes, shorter than a fingerprint"), std::string::npos) << r.out;
  r = tool("to-csv " + log + " -o " + path("o.csv"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.err.find("ODOMETRY: 1 undecodable event(s) skipped"), std::string::npos) << r.err;
  EXPECT_EQ(lines(slurp(path("o.csv"))).size(), 3u);
  // Relative bounds count from the first event (-1 us), absolute ones may be negative too.
  r = tool("cut " + log + " -o " + path("rel.lcmlog") + " --from 0.000006");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(lcmloc::logio::scanLog(path("rel.lcmlog"), [](const lcmloc::logio::RawEvent&) {}).events_read, 2);
  r = tool("cut " + log + " -o " + path("abs.lcmlog") + " --to-utime -1");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(lcmloc::logio::scanLog(path("abs.lcmlog"), [](const lcmloc::logio::RawEvent&) {}).events_read, 1);
}

TEST_F(LogTools, EveryToolReadsATruncatedLogUpToTheDamageAndSaysWhere) {
  const std::string log = path("ref.lcmlog");
  const auto starts = writeReference(log);
  // Cut the file in the middle of its last ODOMETRY event.
  int64_t cut_at = -1, index = -1;
  {
    lcm::LogFile in(log, "r");
    int64_t i = 0;
    while (const lcm::LogEvent* ev = in.readNextEvent()) {
      if (ev->channel == "ODOMETRY") { cut_at = starts[static_cast<std::size_t>(i)]; index = i; }
      ++i;
    }
  }
  ASSERT_GT(cut_at, 0);
  fs::resize_file(log, static_cast<uintmax_t>(cut_at + 40));  // header + part of the channel/payload
  const std::string where = "at byte " + std::to_string(cut_at) + " (event " + std::to_string(index) + ")";

  ToolRun r = tool("info " + log);
  ASSERT_EQ(r.rc, 3) << r.err;  // done, from a damaged log
  EXPECT_NE(r.out.find("DAMAGE in " + log + " " + where), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("truncated"), std::string::npos) << r.out;
  EXPECT_EQ(row(r.out, "ODOMETRY")[2], "98");

  r = tool("to-csv " + log + " -c ODOMETRY -o " + path("o.csv"));
  ASSERT_EQ(r.rc, 3) << r.err;
  EXPECT_NE(r.err.find(where), std::string::npos) << r.err;
  EXPECT_EQ(lines(slurp(path("o.csv"))).size(), 99u);

  r = tool("cut " + log + " -o " + path("cut.lcmlog"));
  ASSERT_EQ(r.rc, 3) << r.err;
  EXPECT_NE(r.err.find(where), std::string::npos) << r.err;
  const auto s = lcmloc::logio::scanLog(path("cut.lcmlog"), [](const lcmloc::logio::RawEvent&) {});
  EXPECT_FALSE(s.damaged);
  EXPECT_EQ(s.events_read, index);  // every intact event before the damage
}

TEST_F(LogTools, ControlCharactersOfChannelNamesDoNotReachTheTerminal) {
  // A channel name may hold any bytes: an escape sequence (clear the screen) and a line of its own.
  const std::string log = path("ctl.lcmlog"), name = "ODO\x1b[2J\nDAMAGE in x";
  {
    lcm::LogFile f(log, "w");
    lcmloc::odometry_t o{};
    o.utime = kT0;
    writeEvent(f, name, kT0, enc(o));
  }
  const ToolRun r = tool("info " + log);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("ODO?[2J?DAMAGE in x"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find('\x1b'), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("\nDAMAGE"), std::string::npos) << r.out;
  const ToolRun csv = tool("to-csv " + log + " -o " + path("csv"));
  ASSERT_EQ(csv.rc, 0) << csv.err;
  EXPECT_EQ(csv.err.find('\x1b'), std::string::npos) << csv.err;
  EXPECT_NE(csv.err.find("ODO?[2J?DAMAGE in x: 1 rows"), std::string::npos) << csv.err;
  // Without -c every channel is selected: '.*' matched no name with a newline, so to-csv found
  // nothing and cut dropped the event.
  const ToolRun cut = tool("cut " + log + " -o " + path("cut.lcmlog"));
  ASSERT_EQ(cut.rc, 0) << cut.err;
  EXPECT_EQ(lcmloc::logio::scanLog(path("cut.lcmlog"), [](const lcmloc::logio::RawEvent&) {}).events_read, 1);
}

TEST_F(LogTools, InfoResynchronisesAfterACorruptEventInTheMiddle) {
  const std::string log = path("ref.lcmlog");
  const auto starts = writeReference(log);
  const std::size_t bad = 40;
  {
    std::fstream f(log, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(starts[bad]);
    f.write("\0\0\0\0", 4);  // destroy the sync word
  }
  const ToolRun r = tool("info " + log);
  ASSERT_EQ(r.rc, 3) << r.err;
  EXPECT_NE(r.out.find("DAMAGE in " + log + " at byte " + std::to_string(starts[bad]) + " (event 40): damaged event"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("resumed at byte " + std::to_string(starts[bad + 1])), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("events:     134 on 5 channels"), std::string::npos) << r.out;
}

TEST_F(LogTools, BadInputGetsAClearErrorAndNonZeroExit) {
  ToolRun r = tool("info " + path("missing.lcmlog"));
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("no such log file"), std::string::npos) << r.err;
  // A directory is no log (it used to read as 4096 damaged bytes, exit 0).
  for (const std::string& cmd : {"info " + dir_.string(), "to-csv " + dir_.string(),
                                 "cut " + dir_.string() + " -o " + path("x.lcmlog")}) {
    r = tool(cmd);
    EXPECT_EQ(r.rc, 2) << cmd;
    EXPECT_NE(r.err.find("is a directory"), std::string::npos) << cmd << "\n" << r.err;
    EXPECT_EQ(r.out.find("DAMAGE"), std::string::npos) << cmd << "\n" << r.out;
  }
  writeReference(path("ref.lcmlog"));
  r = tool("to-csv " + path("ref.lcmlog") + " -c 'NOPE'");
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("no decodable events"), std::string::npos) << r.err;
  r = tool("bogus");
  EXPECT_NE(r.rc, 0);
}

TEST(EventFile, WritesTheStandardFormatThatLcmReads) {
  const std::string file = (fs::temp_directory_path() / ("lcmloc_eventfile_" + std::to_string(::getpid()))).string();
  {
    lcmloc::logger::EventFile f(file, 64);  // small buffer: several writes
    for (int i = 0; i < 10; ++i) {
      std::vector<uint8_t> d(static_cast<std::size_t>(i * 7), static_cast<uint8_t>(i));
      ASSERT_EQ(f.append(1000 + i, "CH" + std::to_string(i), d.data(), d.size()), 0);
    }
    EXPECT_EQ(f.close(), 0);
    EXPECT_EQ(f.eventsWritten(), 10);
    EXPECT_EQ(f.fileBytes(), static_cast<int64_t>(fs::file_size(file)));
  }
  lcm::LogFile in(file, "r");
  int i = 0;
  while (const lcm::LogEvent* ev = in.readNextEvent()) {
    EXPECT_EQ(ev->eventnum, i);
    EXPECT_EQ(ev->timestamp, 1000 + i);
    EXPECT_EQ(ev->channel, "CH" + std::to_string(i));
    ASSERT_EQ(ev->datalen, i * 7);
    for (int k = 0; k < ev->datalen; ++k) EXPECT_EQ(static_cast<const uint8_t*>(ev->data)[k], i);
    ++i;
  }
  EXPECT_EQ(i, 10);
  fs::remove(file);
}

// Many buffers' worth of events (the replay's output writes a buffer each time it is full): every
// event is in the file, in order, as lcm::LogFile reads it; a write that fails is reported by the
// append that made it, and the events of that buffer are not counted as written.
TEST(EventFile, WritesBufferAfterBufferAndReportsAFailureAtOnce) {
  const std::string path =
      (fs::temp_directory_path() / ("lcmloc_eventfile_buffers_" + std::to_string(::getpid()))).string();
  {
    lcmloc::logger::EventFile f(path, 256);  // small buffer: some 200 writes
    for (int i = 0; i < 1000; ++i) {
      std::vector<uint8_t> d(static_cast<std::size_t>(i % 97), static_cast<uint8_t>(i));
      ASSERT_EQ(f.append(1000 + i, "CH" + std::to_string(i % 3), d.data(), d.size()), 0);
    }
    EXPECT_EQ(f.close(false), 0);
    EXPECT_EQ(f.eventsWritten(), 1000);
    EXPECT_EQ(f.fileBytes(), static_cast<int64_t>(fs::file_size(path)));
  }
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  int i = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    EXPECT_EQ(ev->eventnum, i);
    EXPECT_EQ(ev->timestamp, 1000 + i);
    EXPECT_EQ(ev->channel, "CH" + std::to_string(i % 3));
    ASSERT_EQ(ev->datalen, i % 97);
    for (int k = 0; k < ev->datalen; ++k) EXPECT_EQ(static_cast<const uint8_t*>(ev->data)[k], i % 256);
    ++i;
  }
  EXPECT_EQ(i, 1000);
  fs::remove(path);

  // Each event fills the buffer: every append writes.
  const std::vector<uint8_t> d(100, 7);
  lcmloc::logger::EventFile full("/dev/full", 64);
  EXPECT_EQ(full.append(1, "CH", d.data(), d.size()), ENOSPC);
  EXPECT_EQ(full.events(), 0) << "the failed event is dropped";
  EXPECT_EQ(full.eventsWritten(), 0);
  EXPECT_EQ(full.close(false), 0);
}

// An existing file is replaced by a new one (a new inode: nothing of the old file's pages to flush
// when the new one is closed), unless other names would lose it: a hard link keeps seeing the
// file, a symlink is written through.
TEST(EventFile, ReplacesAnOldFileButWritesThroughLinks) {
  const auto dir = fs::temp_directory_path() / ("lcmloc_eventfile_replace_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto inode = [](const fs::path& p) {
    struct stat st {};
    EXPECT_EQ(::lstat(p.c_str(), &st), 0) << p;
    return st.st_ino;
  };
  auto content = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  auto writeLog = [](const fs::path& p) {
    lcmloc::logger::EventFile f(p.string());
    const uint8_t d[3] = {1, 2, 3};
    ASSERT_EQ(f.append(5, "CH", d, sizeof d), 0);
    ASSERT_EQ(f.close(false), 0);
  };
  const std::string old(1000, 'x');
  const fs::path plain = dir / "plain.lcmlog", linked = dir / "linked.lcmlog", other = dir / "other_name.lcmlog",
                 target = dir / "target.lcmlog", sym = dir / "sym.lcmlog";
  for (const auto& p : {plain, linked, target}) std::ofstream(p) << old;
  fs::create_hard_link(linked, other);
  fs::create_symlink(target, sym);
  const auto linked_before = inode(linked), target_before = inode(target);
  std::ifstream held(plain, std::ios::binary);  // (the old file, open: it lives on while held)

  writeLog(plain);
  writeLog(linked);
  writeLog(sym);
  const std::string expected = content(plain);
  EXPECT_EQ(expected.size(), 28u + 2u + 3u) << "one event, nothing of the old content";
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(held), {}), old)
      << "a file of one name is replaced by a new one, not overwritten";
  EXPECT_EQ(inode(linked), linked_before) << "a file of two names is truncated in place";
  EXPECT_EQ(content(other), expected) << "the other name sees the new log";
  EXPECT_TRUE(fs::is_symlink(sym));
  EXPECT_EQ(inode(target), target_before);
  EXPECT_EQ(content(target), expected) << "written through the symlink";
  fs::remove_all(dir);
}

TEST(FileName, ExpandsStrftimeAndIndexAndNeverReusesATakenName) {
  const std::time_t t = 1700000000;  // 2023-11-14 (UTC; local time differs by hours at most)
  using lcmloc::logger::fileName;
  EXPECT_EQ(fileName("/x/log-{index}.lcmlog", 7, t), "/x/log-007.lcmlog");
  EXPECT_EQ(fileName("/x/log-%Y.lcmlog", 0, t), "/x/log-2023.lcmlog");
  const auto dir = fs::temp_directory_path() / ("lcmloc_filename_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string pattern = (dir / "run.lcmlog").string();
  EXPECT_EQ(fileName(pattern, 1, t), pattern) << "free: no suffix";
  std::ofstream((dir / "run.lcmlog").string()) << "x";
  // An earlier recording is kept: file 0 of a new run takes the next free name too.
  EXPECT_EQ(fileName(pattern, 0, t), (dir / "run-001.lcmlog").string());
  EXPECT_EQ(fileName(pattern, 0, t, true), pattern) << "--overwrite";
  EXPECT_EQ(fileName(pattern, 1, t, true, {pattern}), (dir / "run-001.lcmlog").string())
      << "--overwrite never takes a name of the run's own files";
  EXPECT_EQ(fileName(pattern, 1, t), (dir / "run-001.lcmlog").string());
  std::ofstream((dir / "run-001.lcmlog").string()) << "x";
  EXPECT_EQ(fileName(pattern, 1, t), (dir / "run-002.lcmlog").string());
  EXPECT_EQ(fileName(pattern, 0, t), (dir / "run-002.lcmlog").string());
  const std::string indexed = (dir / "log-{index}.lcmlog").string();
  std::ofstream((dir / "log-000.lcmlog").string()) << "x";
  EXPECT_EQ(fileName(indexed, 0, t), (dir / "log-000-001.lcmlog").string()) << "an earlier run's file 0";
  EXPECT_EQ(fileName(indexed, 1, t), (dir / "log-001.lcmlog").string());
  fs::remove_all(dir);
}

TEST(LogWriter, AFullQueueDropsAreCountedPerChannelAndEverythingElseIsWritten) {
  const auto dir = fs::temp_directory_path() / ("lcmloc_logwriter_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  lcmloc::logger::WriterOptions o;
  o.pattern = (dir / "w-{index}.lcmlog").string();
  o.queue_bytes = 4096;  // a 5000-byte message can never be queued: a deterministic drop
  lcmloc::logger::LogWriter w(o);
  for (int i = 0; i < 50; ++i) EXPECT_TRUE(w.push({"SMALL", std::vector<uint8_t>(10, static_cast<uint8_t>(i)), i}));
  EXPECT_FALSE(w.push({"BIG", std::vector<uint8_t>(5000, 0), 50}));
  w.requestRotate();
  for (int i = 51; i < 60; ++i) EXPECT_TRUE(w.push({"SMALL", std::vector<uint8_t>(10, 0), i}));
  w.close();
  const auto s = w.stats();
  EXPECT_EQ(s.written, 59);
  EXPECT_EQ(s.dropped, 1);
  EXPECT_EQ(s.write_lost, 0);
  EXPECT_EQ(s.flushed_events, 59);
  EXPECT_FALSE(s.failed);
  EXPECT_EQ(w.droppedByChannel(), (std::map<std::string, int64_t>{{"BIG", 1}}));
  ASSERT_EQ(w.files().size(), 2u);
  int64_t total = 0;
  for (const auto& f : w.files()) {
    const auto r = lcmloc::logio::scanLog(f, [](const lcmloc::logio::RawEvent& ev) { EXPECT_EQ(*ev.channel, "SMALL"); });
    EXPECT_FALSE(r.damaged);
    total += r.events_read;
  }
  EXPECT_EQ(total, 59);
  EXPECT_EQ(w.files()[1], (dir / "w-001.lcmlog").string());
  fs::remove_all(dir);
}

// A file that is not an LCM log at all (text, no sync word) is said to be so by each command,
// with exit 3 (damaged input), and nothing is made up from it.
TEST_F(LogTools, AFileThatIsNoLogIsSaidToBeNoneByEveryCommand) {
  {
    std::ofstream f(path("notes.lcmlog"));
    for (int i = 0; i < 100; ++i) f << "this is a line of text, not an LCM log\n";
  }
  for (const std::string& args : std::vector<std::string>{"info " + path("notes.lcmlog"), "cut " + path("notes.lcmlog") + " -o " + path("c.lcmlog")}) {
    const ToolRun r = tool(args);
    EXPECT_EQ(r.rc, 3) << args << "\n" << r.out << r.err;
    EXPECT_NE((r.out + r.err).find("no LCM event in the whole file (3900 bytes, no sync word 0xEDA1DA01"),
              std::string::npos)
        << args << "\n" << r.out << r.err;
  }
}
