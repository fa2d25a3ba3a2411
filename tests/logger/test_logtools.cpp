// lcmloc-log (info, to-csv, cut) on logs the tests write with lcm::LogFile (the writer
// lcm-logger uses) and with our EventFile; damaged logs; the file-name pattern.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/eval/log_reader.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/logger/event_file.hpp"
#include "lcmloc/logger/log_writer.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"

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

  /// The reference log: ODOMETRY at 100 Hz with seq 50 missing, POSE (arrays), HEARTBEAT from
  /// two processes, RAW of an unknown type, one undecodable ODOMETRY_BAD event.
  /// Returns the byte offset of every event.
  std::vector<int64_t> writeReference(const std::string& file) {
    std::vector<int64_t> starts;
    lcm::LogFile log(file, "w");
    EXPECT_TRUE(log.good());
    auto put = [&](const std::string& ch, int64_t t, const std::vector<uint8_t>& data) {
      starts.push_back(ftello(log.getFilePtr()));
      lcm::LogEvent ev;
      ev.eventnum = 0;
      ev.timestamp = t;
      ev.channel = ch;
      ev.datalen = static_cast<int32_t>(data.size());
      ev.data = const_cast<uint8_t*>(data.data());
      ASSERT_EQ(log.writeEvent(&ev), 0);
    };
    auto enc = [](const auto& m) {
      std::vector<uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(b.data(), 0, static_cast<int>(b.size()));
      return b;
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
  // Several channels to a directory in which one CHANNEL.csv is the log itself.
  fs::create_directories(path("d"));
  fs::create_hard_link(log, path("d/POSE.csv"));
  const ToolRun dir = tool("to-csv " + log + " -o " + path("d"));
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
    return lcmloc::eval::scanLog(path("cut.lcmlog"), [](const lcmloc::eval::RawEvent&) {}).events_read;
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
  EXPECT_EQ(lcmloc::eval::scanLog(path("rel.lcmlog"), [](const lcmloc::eval::RawEvent&) {}).events_read, 2);
  r = tool("cut " + log + " -o " + path("abs.lcmlog") + " --to-utime -1");
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(lcmloc::eval::scanLog(path("abs.lcmlog"), [](const lcmloc::eval::RawEvent&) {}).events_read, 1);
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
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("DAMAGE in " + log + " " + where), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("truncated"), std::string::npos) << r.out;
  EXPECT_EQ(row(r.out, "ODOMETRY")[2], "98");

  r = tool("to-csv " + log + " -c ODOMETRY -o " + path("o.csv"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.err.find(where), std::string::npos) << r.err;
  EXPECT_EQ(lines(slurp(path("o.csv"))).size(), 99u);

  r = tool("cut " + log + " -o " + path("cut.lcmlog"));
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.err.find(where), std::string::npos) << r.err;
  const auto s = lcmloc::eval::scanLog(path("cut.lcmlog"), [](const lcmloc::eval::RawEvent&) {});
  EXPECT_FALSE(s.damaged);
  EXPECT_EQ(s.events_read, index);  // every intact event before the damage
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
  ASSERT_EQ(r.rc, 0) << r.err;
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
    const auto r = lcmloc::eval::scanLog(f, [](const lcmloc::eval::RawEvent& ev) { EXPECT_EQ(*ev.channel, "SMALL"); });
    EXPECT_FALSE(r.damaged);
    total += r.events_read;
  }
  EXPECT_EQ(total, 59);
  EXPECT_EQ(w.files()[1], (dir / "w-001.lcmlog").string());
  fs::remove_all(dir);
}
