// Offline replay: determinism, recorded hot swaps, damaged logs, checkpoints (in process, and the
// lcmloc-replay executable on a damaged log).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <variant>

#include <lcm/lcm-cpp.hpp>

#include "process_fixture.hpp"
#include "daemon/checkpoint.hpp"
#include "daemon/daemon.hpp"
#include "lcmloc/drivers/scenario_map.hpp"
#include "lcmloc/bus/convert.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/replay/log_bus.hpp"
#include "lcmloc/replay/replay.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

using Event = LogEvent;

void writeEvents(const std::string& path, const std::vector<Event>& events) {
  lcm::LogFile log(path, "w");
  for (const auto& e : events) {
    lcm::LogEvent ev;
    ev.eventnum = 0;
    ev.timestamp = e.timestamp;
    ev.channel = e.channel;
    ev.datalen = static_cast<int32_t>(e.data.size());
    ev.data = const_cast<uint8_t*>(e.data.data());
    log.writeEvent(&ev);
  }
}

template <typename T>
Event encode(const std::string& channel, const T& m) {
  Event e{m.utime, channel, std::vector<uint8_t>(static_cast<std::size_t>(m.getEncodedSize()))};
  m.encode(e.data.data(), 0, static_cast<int>(e.data.size()));
  return e;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class ReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("lcmloc_replay_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cfg_ = simconfig::loadSimSystemConfig(LCMLOC_PAPER_YAML);
    cfg_.scenario = replay::ovalScenario(cfg_.scenario, replay::OvalTrack{}, 60.0);
    cfg_.fusion.shadow.clear();
    cfg_.fusion.map_file = path("map.csv");  // the daemon's map: the oval's markers
    drivers::writeScenarioMap(cfg_, cfg_.fusion.map_file);
    log_ = path("in.lcmlog");
    stats_ = replay::writeSyntheticLog(cfg_.scenario, 60.0, log_, cfg_.channels);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  replay::ReplayResult run(const std::string& in, const std::string& out, const simconfig::SimSystemConfig& cfg) {
    replay::ReplayOptions o;
    o.input = in;
    o.output = out;
    o.progress_period_s = 0;
    return replay::replayLog(cfg, o);
  }

  fs::path dir_;
  simconfig::SimSystemConfig cfg_;
  std::string log_;
  replay::SyntheticLogStats stats_;
};

}  // namespace

TEST_F(ReplayTest, SameLogAndConfigGiveByteIdenticalOutput) {
  ASSERT_GT(stats_.odometry, 5000);
  ASSERT_GT(stats_.detections, 20);
  cfg_.fusion.shadow = {"dead_reckoning"};
  const auto a = run(log_, path("a.lcmlog"), cfg_);
  const auto b = run(log_, path("b.lcmlog"), cfg_);
  EXPECT_FALSE(a.damaged);
  EXPECT_EQ(a.events_read, stats_.odometry + stats_.detections);
  EXPECT_EQ(a.used, stats_.odometry + stats_.detections);
  EXPECT_EQ(a.rejected, 0);
  EXPECT_EQ(a.written_per_channel.at("POSE"), a.used);
  EXPECT_EQ(a.written_per_channel.at("POSE_DEAD_RECKONING"), a.used);
  EXPECT_EQ(a.written_per_channel.at("GATE"), 2 * stats_.detections);  // active + shadow decisions
  const std::string fa = slurp(path("a.lcmlog")), fb = slurp(path("b.lcmlog"));
  ASSERT_GT(fa.size(), 100000u);
  EXPECT_TRUE(fa == fb) << "two replays of the same log differ";

  // Message utime = measurement time, POSE seq counts 0, 1, 2, ...; event timestamps = utime.
  int64_t seq = 0, last = -1;
  int accepted = 0;
  for (const auto& e : readLog(path("a.lcmlog"))) {
    if (e.channel == "POSE") {
      const auto p = decode<lcmloc::pose_t>(e);
      EXPECT_EQ(p.seq, seq++);
      EXPECT_EQ(p.utime, e.timestamp);
      EXPECT_GE(p.utime, last);
      last = p.utime;
    }
    if (e.channel == "GATE") accepted += decode<lcmloc::gate_decision_t>(e).accepted;
  }
  EXPECT_GT(accepted, stats_.detections / 2) << "the gated UKF should accept most genuine markers";

  // With the inputs copied, the output holds them too, each with its message time.
  replay::ReplayOptions o;
  o.input = log_;
  o.output = path("c.lcmlog");
  o.with_inputs = true;
  o.progress_period_s = 0;
  const auto c = replay::replayLog(cfg_, o);
  EXPECT_EQ(c.copied, a.events_read);
  EXPECT_EQ(c.written, a.written + a.events_read);
}

// fusion.output_every: fewer POSE events (every 10th odometry + one per detection + the last),
// the same GATE decisions, still byte-identical from run to run.
TEST_F(ReplayTest, OutputEveryDecimatesPosesKeepsDecisionsAndIsDeterministic) {
  cfg_.fusion.shadow = {"dead_reckoning"};
  const auto per = run(log_, path("per.lcmlog"), cfg_);
  cfg_.fusion.output_every = 10;
  const auto a = run(log_, path("a.lcmlog"), cfg_);
  const auto b = run(log_, path("b.lcmlog"), cfg_);
  EXPECT_EQ(a.used, per.used);
  EXPECT_EQ(a.written_per_channel.at("GATE"), per.written_per_channel.at("GATE"));
  const int64_t poses = a.written_per_channel.at("POSE");
  EXPECT_GE(poses, stats_.odometry / 10 + stats_.detections);
  EXPECT_LE(poses, stats_.odometry / 10 + stats_.detections + 1);
  EXPECT_EQ(a.written_per_channel.at("POSE_DEAD_RECKONING"), poses);
  const std::string fa = slurp(path("a.lcmlog")), fb = slurp(path("b.lcmlog"));
  ASSERT_GT(fa.size(), 10000u);
  EXPECT_TRUE(fa == fb) << "two replays of the same log differ";
  // Same decisions at the same times; the last POSE is the state after the last input.
  std::vector<lcmloc::gate_decision_t> dp, da;
  for (const auto& e : readLog(path("per.lcmlog")))
    if (e.channel == "GATE") dp.push_back(decode<lcmloc::gate_decision_t>(e));
  int64_t last_pose_utime = 0, last_input_utime = 0;
  for (const auto& e : readLog(path("a.lcmlog"))) {
    if (e.channel == "GATE") da.push_back(decode<lcmloc::gate_decision_t>(e));
    if (e.channel == "POSE") last_pose_utime = decode<lcmloc::pose_t>(e).utime;
  }
  for (const auto& e : readLog(log_)) last_input_utime = std::max(last_input_utime, e.timestamp);
  EXPECT_EQ(last_pose_utime, last_input_utime);
  ASSERT_EQ(dp.size(), da.size());
  for (std::size_t i = 0; i < dp.size(); ++i) {
    EXPECT_EQ(dp[i].utime, da[i].utime) << i;
    EXPECT_EQ(dp[i].accepted, da[i].accepted) << i;
    EXPECT_EQ(dp[i].marker_id, da[i].marker_id) << i;
  }
}

TEST_F(ReplayTest, RecordedSwitchesArePerformedAtTheSamePointWithoutGapOrJump) {
  // Insert control commands at fixed message times into the log (as the logger records them).
  auto events = readLog(log_);
  const int64_t t0 = events.front().timestamp;
  struct Cmd { double at_s; std::string filter, params; };
  const std::vector<Cmd> cmds{{10.0, "ukf_calib", ""},
                              {20.0, "no_such_filter", ""},        // refused: unknown
                              {25.0, "ukf", "{bogus: 1}"},         // refused: bad parameter
                              {30.0, "dead_reckoning", ""},
                              {40.0, "ukf_gated", "{gate: {value: 6.635}}"}};
  std::vector<Event> with;
  std::size_t next = 0;
  for (const auto& e : events) {
    while (next < cmds.size() && e.timestamp >= t0 + static_cast<int64_t>(cmds[next].at_s * 1e6)) {
      lcmloc::fusion_control_t c{};
      c.utime = e.timestamp - 3;  // between two odometry messages
      c.seq = static_cast<int64_t>(next);
      c.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER;
      c.filter = cmds[next].filter;
      c.parameters = cmds[next].params;
      with.push_back(encode("FUSION_CONTROL", c));
      ++next;
    }
    with.push_back(e);
  }
  ASSERT_EQ(next, cmds.size());
  const std::string switched = path("switched.lcmlog");
  writeEvents(switched, with);

  const auto r1 = run(switched, path("out1.lcmlog"), cfg_);
  const auto r2 = run(switched, path("out2.lcmlog"), cfg_);
  EXPECT_TRUE(slurp(path("out1.lcmlog")) == slurp(path("out2.lcmlog")));
  EXPECT_EQ(r1.final_filter, "ukf_gated");
  EXPECT_EQ(r1.used, stats_.odometry + stats_.detections + static_cast<int64_t>(cmds.size()) - 2);

  // Reference: the same log without switches (the gated UKF throughout).
  const auto ref_events = (run(log_, path("ref.lcmlog"), cfg_), readLog(path("ref.lcmlog")));
  std::vector<lcmloc::pose_t> ref;
  for (const auto& e : ref_events)
    if (e.channel == "POSE") ref.push_back(decode<lcmloc::pose_t>(e));

  std::vector<lcmloc::pose_t> poses;
  std::vector<lcmloc::fusion_status_t> status;
  for (const auto& e : readLog(path("out1.lcmlog"))) {
    if (e.channel == "POSE") poses.push_back(decode<lcmloc::pose_t>(e));
    if (e.channel == "FUSION_STATUS") status.push_back(decode<lcmloc::fusion_status_t>(e));
  }
  // No gap: one POSE per odometry and ruler input, exactly at the times of the reference.
  ASSERT_EQ(poses.size(), static_cast<std::size_t>(stats_.odometry + stats_.detections));
  std::size_t switches = 0;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    EXPECT_GE(poses[i].utime, poses[i - 1].utime);
    EXPECT_LE(poses[i].utime - poses[i - 1].utime, 10000) << "gap in the pose output at " << poses[i].utime;
    if (poses[i].filter == poses[i - 1].filter) continue;
    ++switches;
    // No jump beyond the covariance: the first pose of the new filter is where the old filter's
    // state, moved by one odometry step, lies (well within 3 sigma of the old covariance).
    const auto& a = poses[i - 1];
    const auto& b = poses[i];
    const double jump = std::hypot(b.state[0] - a.state[0], b.state[1] - a.state[1]);
    const double sigma = std::sqrt(a.covariance[0][0] + a.covariance[1][1]);
    EXPECT_LT(jump, 0.03 + 3 * sigma) << a.filter << " -> " << b.filter << " at " << b.utime;
    EXPECT_LT(jump, 0.05) << a.filter << " -> " << b.filter;
    EXPECT_NEAR(b.covariance[0][0], a.covariance[0][0], 0.5 * a.covariance[0][0] + 1e-4);
  }
  EXPECT_EQ(switches, 3u);
  // Before the first switch the output equals the reference exactly.
  ASSERT_EQ(ref.size(), poses.size());
  std::size_t same = 0;
  for (std::size_t i = 0; i < poses.size() && poses[i].utime < t0 + 10000000 - 3; ++i, ++same) {
    EXPECT_EQ(poses[i].utime, ref[i].utime);
    EXPECT_EQ(poses[i].state, ref[i].state);
  }
  EXPECT_GT(same, 900u);
  auto has = [&](const std::string& ev, const std::string& what) {
    for (const auto& s : status)
      if (s.event == ev && s.detail.find(what) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("ack", "switched ukf_gated -> ukf_calib"));
  EXPECT_TRUE(has("refused", "unknown filter type 'no_such_filter'"));
  EXPECT_TRUE(has("refused", "bogus: unknown key"));
  EXPECT_TRUE(has("ack", "switched ukf_calib -> dead_reckoning"));
  EXPECT_TRUE(has("ack", "switched dead_reckoning -> ukf_gated"));
  EXPECT_EQ(status.back().event, "stopped");
}

TEST_F(ReplayTest, DamagedLogIsReplayedUpToTheDamageAndSaysWhere) {
  auto events = readLog(log_);
  // Byte offsets of the events in the file.
  std::vector<int64_t> offset{0};
  for (const auto& e : events) offset.push_back(offset.back() + 28 + static_cast<int64_t>(e.channel.size() + e.data.size()));
  std::string bytes = slurp(log_);
  ASSERT_EQ(static_cast<int64_t>(bytes.size()), offset.back());
  const std::size_t bad = 1000;
  bytes[static_cast<std::size_t>(offset[bad])] = 'X';                        // corrupt sync word of event 1000
  bytes.resize(static_cast<std::size_t>(offset[events.size() - 1] + 20));   // last event truncated
  const std::string damaged = path("damaged.lcmlog");
  std::ofstream(damaged, std::ios::binary) << bytes;

  const auto r = run(damaged, path("out.lcmlog"), cfg_);
  EXPECT_TRUE(r.damaged);
  ASSERT_EQ(r.issues.size(), 2u);
  // The damaged stretch holds the corrupt header. LCM's reader also refuses the event before a
  // corrupt header (its length cannot be trusted), so the stretch starts one event early.
  const auto& d = r.issues[0];
  EXPECT_LE(d.byte_offset, offset[bad]);
  EXPECT_GE(d.byte_offset, offset[bad - 1]);
  EXPECT_EQ(d.event_index, d.byte_offset == offset[bad] ? static_cast<int64_t>(bad) : static_cast<int64_t>(bad - 1));
  EXPECT_NE(d.what.find("resumed at byte " + std::to_string(offset[bad + 1])), std::string::npos) << d.what;
  const int64_t lost = static_cast<int64_t>(bad) + 1 - d.event_index;
  EXPECT_EQ(r.events_read, static_cast<int64_t>(events.size()) - 1 - lost);
  EXPECT_EQ(r.issues[1].byte_offset, offset[events.size() - 1]);
  EXPECT_EQ(r.issues[1].event_index, r.events_read);
  EXPECT_NE(r.issues[1].what.find("truncated"), std::string::npos) << r.issues[1].what;
  EXPECT_EQ(r.gaps, lost);  // the lost events show as sequence gaps (bad is an odometry event)
  // The bytes not read: the damaged stretch up to where reading resumed, and the truncated tail.
  EXPECT_EQ(r.bytes_unreadable, (offset[bad + 1] - d.byte_offset) + 20);

  // The executable says the same, exits 3 and still writes the output.
  Child exe(LCMLOC_REPLAY, {damaged, "-o", path("exe.lcmlog"), "--config", LCMLOC_PAPER_YAML, "--no-shadow"},
            path("exe.out"));
  const auto rc = exe.wait(60s);
  ASSERT_TRUE(rc.has_value());
  EXPECT_EQ(*rc, 3) << exe.output();
  const std::string out = exe.output();
  EXPECT_NE(out.find("damage: before event " + std::to_string(d.event_index) + " at byte " +
                     std::to_string(d.byte_offset)),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("truncated"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(path("exe.lcmlog")));

  Child missing(LCMLOC_REPLAY, {path("nope.lcmlog"), "-o", path("x.lcmlog"), "--config", LCMLOC_PAPER_YAML},
                path("missing.out"));
  EXPECT_EQ(missing.wait(30s).value_or(-1), 2) << missing.output();  // a usage error
  EXPECT_NE(missing.output().find("no such file"), std::string::npos) << missing.output();
}

TEST_F(ReplayTest, AnOutputThatCannotBeWrittenIsAnErrorNotASuccess) {
  // A full disk: the replay said "write ... failed", then "written 3170" and exited 0.
  Child full(LCMLOC_REPLAY, {log_, "-o", "/dev/full", "--config", LCMLOC_PAPER_YAML}, path("full.out"));
  EXPECT_EQ(full.wait(30s).value_or(-1), 1) << full.output();
  EXPECT_NE(full.output().find("could not be written (No space left on device)"), std::string::npos) << full.output();
  EXPECT_EQ(full.output().find(", written "), std::string::npos) << full.output();  // no summary of success
  // A file-size limit: SIGXFSZ killed it (exit 153) with a torn last event; now EFBIG is an
  // error and the output holds whole events only. (The limit holds for the file that takes the
  // replay's own output too: warnings only, or the lines before the error, which comes a buffer of
  // the output after the write that failed, would fill it.)
  const std::string out = path("limited.lcmlog");
  Child limited("/usr/bin/prlimit", {"--fsize=2000", LCMLOC_REPLAY, log_, "--with-inputs", "-o", out, "--config",
                                     LCMLOC_PAPER_YAML, "--log-level", "warn"},
                path("limited.out"));
  EXPECT_EQ(limited.wait(30s).value_or(-1), 1) << limited.output();
  EXPECT_NE(limited.output().find("could not be written (File too large)"), std::string::npos) << limited.output();
  std::vector<logio::LogIssue> issues;
  logio::LogScanner scanner(out, &issues);
  while (scanner.next()) {}
  EXPECT_FALSE(scanner.damaged()) << (issues.empty() ? "" : issues[0].what);
  EXPECT_GT(scanner.eventsRead(), 0);
  EXPECT_LE(fs::file_size(out), 2000u);
}

/// What a replay reports, in one string to compare.
std::string describe(const replay::ReplayResult& r) {
  std::string s = "read " + std::to_string(r.events_read) + " old " + std::to_string(r.old_outputs) + " dispatched " +
                  std::to_string(r.dispatched) + " in " + std::to_string(r.messages_in) + " used " +
                  std::to_string(r.used) + " rejected " + std::to_string(r.rejected) + " gaps " +
                  std::to_string(r.gaps) + " written " + std::to_string(r.written) + " copied " +
                  std::to_string(r.copied) + " unreadable " + std::to_string(r.bytes_unreadable) +
                  (r.damaged ? " damaged" : "") + (r.interrupted ? " interrupted" : "") + " filter " +
                  r.final_filter + " error '" + r.write_error + "'";
  for (const auto& [ch, n] : r.written_per_channel) s += " " + ch + "=" + std::to_string(n);
  for (const auto& is : r.issues) s += "; " + is.describe();
  return s;
}

// The replay reads on a thread of its own (ReplayOptions::read_ahead, the default) or in line: the
// same bytes and the same report either way, over damage, recorded outputs, commands, undecodable
// and invalid messages, copied inputs, an early stop and an output that fails.
TEST_F(ReplayTest, ReadingAheadOnAThreadGivesWhatReadingInLineGives) {
  auto events = readLog(log_);
  ASSERT_GT(events.size(), 6000u);
  std::vector<Event> mixed;
  for (std::size_t i = 0; i < events.size(); ++i) {
    mixed.push_back(events[i]);
    if (i == 100) {  // a recorded output of the live run: ignored
      lcmloc::pose_t p{};
      p.utime = events[i].timestamp;
      p.filter = "ukf_gated";
      mixed.push_back(encode("POSE", p));
    }
    if (i == 2000) {  // a switch, and one refused
      lcmloc::fusion_control_t c{};
      c.utime = events[i].timestamp + 1;
      c.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER;
      c.filter = "ukf_calib";
      mixed.push_back(encode("FUSION_CONTROL", c));
      c.seq = 1;
      c.filter = "no_such_filter";
      mixed.push_back(encode("FUSION_CONTROL", c));
    }
    if (i == 3000) mixed.push_back({events[i].timestamp, "ODOMETRY", std::vector<uint8_t>(12, 0xab)});  // undecodable
    if (i == 4000) {  // invalid: NaN
      lcmloc::odometry_t o{};
      o.utime = events[i].timestamp;
      o.seq = 999999;
      o.delta_s = std::nan("");
      mixed.push_back(encode("ODOMETRY", o));
    }
    if (i % 1500 == 700) mixed.push_back({events[i].timestamp, "SOMETHING_ELSE", std::vector<uint8_t>(40, 1)});
  }
  writeEvents(path("mixed.lcmlog"), mixed);
  std::string bytes = slurp(path("mixed.lcmlog"));
  // Damage: a corrupt sync word in the middle and a truncated last event.
  std::size_t at = 0;
  for (std::size_t i = 0; i < 5000; ++i) at += 28 + mixed[i].channel.size() + mixed[i].data.size();
  bytes[at] = 'X';
  bytes.resize(bytes.size() - 7);
  std::ofstream(path("damaged.lcmlog"), std::ios::binary) << bytes;

  auto both = [&](const std::string& input, const std::string& output, bool with_inputs, int stop_after) {
    std::string report[2], file[2];
    for (int ahead = 0; ahead < 2; ++ahead) {
      replay::ReplayOptions o;
      o.input = input;
      o.output = output.empty() || output == "/dev/full" ? output : output + std::to_string(ahead);
      o.with_inputs = with_inputs;
      o.progress_period_s = 0;
      o.read_ahead = ahead == 1;
      int polled = 0;
      if (stop_after > 0) o.stop = [&polled, stop_after] { return ++polled > stop_after; };
      const replay::ReplayResult r = replay::replayLog(cfg_, o);
      report[ahead] = describe(r);
      // Each side's CPU time: some, and no more than the wall time (inline, both together).
      EXPECT_GT(r.reading_cpu_s, 0.0);
      EXPECT_GT(r.applying_cpu_s, 0.0);
      EXPECT_LE(r.reading_cpu_s, r.seconds + 1e-3);
      EXPECT_LE(r.applying_cpu_s, r.seconds + 1e-3);
      if (!o.read_ahead) {
        EXPECT_LE(r.reading_cpu_s + r.applying_cpu_s, r.seconds + 1e-3);
      }
      if (!output.empty() && output != "/dev/full") file[ahead] = slurp(o.output);
    }
    EXPECT_EQ(report[1], report[0]) << input << " -> " << output;
    EXPECT_TRUE(file[1] == file[0]) << input << " -> " << output << ": the outputs differ";
    return report[0];
  };
  const std::string full = both(path("damaged.lcmlog"), path("out"), true, 0);
  EXPECT_NE(full.find("damaged"), std::string::npos) << full;
  EXPECT_NE(full.find("old 1 "), std::string::npos) << full;
  EXPECT_NE(full.find("rejected 2 "), std::string::npos) << full;  // the undecodable and the NaN ones
  EXPECT_NE(full.find("FUSION_STATUS"), std::string::npos) << full;
  both(path("damaged.lcmlog"), path("plain"), false, 0);
  both(path("damaged.lcmlog"), "", false, 0);  // no output file
  const std::string stopped = both(path("damaged.lcmlog"), path("stop"), false, 10);
  EXPECT_NE(stopped.find("read 2560 "), std::string::npos) << stopped;  // polled every 256 events
  EXPECT_NE(stopped.find("interrupted"), std::string::npos) << stopped;
  // An output that fails (a full disk) when its first buffer is written out: the replay stops
  // there, at the same event either way.
  for (int k = 0; k < 3; ++k) mixed.insert(mixed.end(), mixed.begin(), mixed.begin() + 6000);  // (over 1 MB)
  writeEvents(path("long.lcmlog"), mixed);
  const std::string failed = both(path("long.lcmlog"), "/dev/full", true, 0);
  EXPECT_NE(failed.find("No space left on device"), std::string::npos) << failed;
  EXPECT_EQ(failed.find("read " + std::to_string(mixed.size()) + " "), std::string::npos) << failed;
  // A log shorter than a block, and an empty one.
  writeEvents(path("short.lcmlog"), std::vector<Event>(events.begin(), events.begin() + 50));
  EXPECT_NE(both(path("short.lcmlog"), path("short"), true, 0).find("read 50 "), std::string::npos);
  writeEvents(path("empty.lcmlog"), {});
  EXPECT_NE(both(path("empty.lcmlog"), path("empty"), false, 0).find("read 0 "), std::string::npos);

  // lcmloc-replay --one-thread: the same output file and summary as the default.
  std::string summary[2];
  for (int one = 0; one < 2; ++one) {
    std::vector<std::string> args{path("damaged.lcmlog"), "-o", path("exe" + std::to_string(one) + ".lcmlog"),
                                  "--config", LCMLOC_PAPER_YAML, "--with-inputs"};
    if (one) args.push_back("--one-thread");
    Child exe(LCMLOC_REPLAY, args, path("exe" + std::to_string(one) + ".out"));
    EXPECT_EQ(exe.wait(60s).value_or(-1), 3) << exe.output();  // (damaged)
    const std::string out = exe.output();
    const auto at = out.find("\nread ");  // the summary line
    ASSERT_NE(at, std::string::npos) << out;
    summary[one] = out.substr(at, out.find("; final filter", at) - at);
  }
  EXPECT_EQ(summary[1], summary[0]);
  EXPECT_TRUE(slurp(path("exe0.lcmlog")) == slurp(path("exe1.lcmlog")));
}

// The intake converts an odometry message straight into the item it is given, whatever that item
// held before (the replay's items are reused, block after block): a detection, a refused message,
// an odometry input.
TEST(DaemonIntakeTest, ConvertsOdometryInPlaceIntoAnItemOfAnyKind) {
  const simconfig::SimSystemConfig cfg = simconfig::loadSimSystemConfig(LCMLOC_PAPER_YAML);
  fusion::DaemonIntake intake(cfg);
  fusion::IntakeItem item;
  lcmloc::magruler_t r{};
  r.utime = 1000;
  r.seq = 4;
  r.num_sensors = 2;
  r.readings = {0.5, 0.5};
  r.detected = true;
  r.lateral_offset = 0.05;
  r.quality = 0.9;
  intake.take(cfg.channels.magruler.front(), r, item);
  ASSERT_EQ(item.kind, fusion::IntakeItem::Kind::Input);
  ASSERT_TRUE(std::holds_alternative<core::RulerDetection>(item.input.payload));

  lcmloc::odometry_t o{};
  o.utime = 2000;
  o.seq = 7;
  o.delta_s = 0.25;
  o.steering = 0.1;
  o.has_steering = true;
  o.delta_theta = 0.003;
  intake.take(cfg.channels.odometry, o, item);
  ASSERT_EQ(item.kind, fusion::IntakeItem::Kind::Input);
  ASSERT_TRUE(std::holds_alternative<core::OdometryInput>(item.input.payload));
  const auto expect = [&](const lcmloc::odometry_t& m) {
    const auto& in = std::get<core::OdometryInput>(item.input.payload);
    EXPECT_EQ(item.input.channel, cfg.channels.odometry);
    EXPECT_EQ(item.input.seq, m.seq);
    EXPECT_EQ(item.input.utime, m.utime);
    EXPECT_EQ(in.utime, m.utime);
    EXPECT_EQ(in.delta_s, m.delta_s);
    EXPECT_EQ(in.steering, m.steering);
    EXPECT_EQ(in.has_steering, m.has_steering);
    EXPECT_EQ(in.delta_theta, m.delta_theta);
  };
  expect(o);

  lcmloc::odometry_t bad = o;  // refused: the reason with it, the kind says so
  bad.seq = 8;
  bad.utime = 3000;
  bad.delta_s = std::nan("");
  intake.take(cfg.channels.odometry, bad, item);
  EXPECT_EQ(item.kind, fusion::IntakeItem::Kind::Rejected);
  EXPECT_NE(item.why.find("delta_s"), std::string::npos) << item.why;
  EXPECT_EQ(item.input.seq, 8);

  lcmloc::odometry_t next = o;  // into the item that held the refused one
  next.seq = 9;
  next.utime = 4000;
  next.delta_s = -0.1;
  next.has_steering = false;
  next.delta_theta = -0.02;
  intake.take(cfg.channels.odometry, next, item);
  EXPECT_EQ(item.kind, fusion::IntakeItem::Kind::Input);
  expect(next);

  lcmloc::magruler_t raw = r;  // a reading without a detection: counted, nothing for the filters
  raw.seq = 5;
  raw.detected = false;
  intake.take(cfg.channels.magruler.front(), raw, item);
  EXPECT_EQ(item.kind, fusion::IntakeItem::Kind::Nothing);
  EXPECT_FALSE(item.seq_event);
  raw.seq = 7;  // two lost on that channel: the item says so
  intake.take(cfg.channels.magruler.front(), raw, item);
  EXPECT_EQ(item.kind, fusion::IntakeItem::Kind::Nothing);
  EXPECT_TRUE(item.seq_event);
  EXPECT_EQ(item.gap.missing, 1);
}

TEST_F(ReplayTest, OutputOverTheInputIsRefusedAndTheInputKept) {
  const std::string before = slurp(log_);
  EXPECT_THROW(run(log_, log_, cfg_), std::runtime_error);
  const std::string link = path("link.lcmlog");  // the same file under another name
  fs::create_symlink(log_, link);
  EXPECT_THROW(run(log_, link, cfg_), std::runtime_error);
  EXPECT_EQ(slurp(log_), before);  // not truncated

  Child exe(LCMLOC_REPLAY, {log_, "-o", link, "--config", LCMLOC_PAPER_YAML}, path("same.out"));
  EXPECT_EQ(exe.wait(30s).value_or(-1), 2) << exe.output();  // a bad argument
  EXPECT_NE(exe.output().find("is the input log"), std::string::npos) << exe.output();
  EXPECT_EQ(slurp(log_), before);
}

TEST_F(ReplayTest, CheckpointRoundTripsExactlyAndRejectsGarbage) {
  core::FilterState s;
  s.utime = 123456789;
  s.x = Eigen::VectorXd::LinSpaced(5, 0.1, 0.5);
  s.P = Eigen::MatrixXd::Identity(5, 5) * 1e-3;
  s.P(0, 1) = s.P(1, 0) = 1.0 / 3.0e4;
  s.names = {"x", "y", "theta", "odo_scale", "steer_bias"};
  fusion::writeCheckpoint(path("ck"), s, "ukf_calib");
  const auto c = fusion::readCheckpoint(path("ck"));
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->filter, "ukf_calib");
  EXPECT_EQ(c->state.utime, s.utime);
  EXPECT_EQ(c->state.x, s.x);
  EXPECT_EQ(c->state.P, s.P);
  EXPECT_EQ(c->state.names, s.names);
  EXPECT_FALSE(fusion::readCheckpoint(path("absent")).has_value());
  std::ofstream(path("garbage")) << "not a checkpoint";
  EXPECT_THROW(fusion::readCheckpoint(path("garbage")), std::runtime_error);
  // A covariance no filter can start from (zero, a negative variance, not positive
  // semi-definite): refused with the reason. Taken as it was, a zero covariance froze the filter
  // at the checkpoint's pose (every marker refused, the frozen state written back).
  auto refuses = [&](const Eigen::MatrixXd& P, const std::string& why) {
    core::FilterState bad = s;
    bad.P = P;
    fusion::writeCheckpoint(path("bad.ck"), bad, "ukf_calib");
    try {
      fusion::readCheckpoint(path("bad.ck"));
      ADD_FAILURE() << "accepted: " << why;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  refuses(Eigen::MatrixXd::Zero(5, 5), "the variance of x is not > 0");
  Eigen::MatrixXd neg = s.P;
  neg(2, 2) = -1.0;
  refuses(neg, "the variance of theta is not > 0");
  Eigen::MatrixXd indefinite = s.P;
  indefinite(0, 1) = indefinite(1, 0) = 0.01;  // correlation 10
  refuses(indefinite, "not positive semi-definite");
  Eigen::MatrixXd asym = s.P;
  asym(0, 1) = 0.0;
  refuses(asym, "not symmetric");

  EXPECT_EQ(fusion::checkpointUnwritable(path("new.ck")), "");
  EXPECT_FALSE(fs::exists(path("new.ck.tmp")));  // the probe is removed again
  EXPECT_NE(fusion::checkpointUnwritable(path("no/such/dir/ck")).find("No such file or directory"), std::string::npos);
}

TEST_F(ReplayTest, AHandOverFromTheBusCoversEveryQueuedInputHoweverOld) {
  // Make before break: the new daemon queues the inputs for as long as the old one keeps running,
  // which may be many seconds. Those more than fusion.max_time_jump older than the old daemon's
  // last POSE were taken as another time base and processed again: POSE went back in time.
  auto run = [&](bool saw_queued, const std::string& out) {
    replay::LogBus bus(out);
    fusion::FusionDaemon daemon(cfg_, bus, fusion::FusionDaemon::Options{true});
    lcmloc::odometry_t o{};
    o.delta_s = 0.1;
    std::vector<uint8_t> buf;
    auto send = [&](int64_t k) {
      o.utime = 1000000 + k * 10000;
      o.seq = k;
      buf.resize(static_cast<std::size_t>(o.getEncodedSize()));
      o.encode(buf.data(), 0, static_cast<int>(buf.size()));
      EXPECT_EQ(bus.dispatch(cfg_.channels.odometry, buf.data(), buf.size(), o.utime), 1);
    };
    for (int64_t k = 0; k < 500; ++k) send(k);  // 5 s queued
    core::FilterState init;
    init.utime = 1000000 + 499 * 10000;  // the old daemon's last POSE: after the last queued input
    init.x = Eigen::Vector3d(50.0, 2.0, 0.0);
    init.P = Eigen::Matrix3d::Identity() * 1e-4;
    init.names = {"x", "y", "theta"};
    daemon.release(init, "test", saw_queued);
    const int64_t processed = daemon.processed(), covered = daemon.covered();
    send(500);
    daemon.shutdown();
    bus.close();
    std::vector<int64_t> pose_times;
    for (const auto& ev : readLog(out))
      if (ev.channel == cfg_.channels.pose) pose_times.push_back(decode<lcmloc::pose_t>(ev).utime);
    return std::make_tuple(processed, covered, pose_times);
  };
  const auto [processed, covered, poses] = run(true, path("handover.lcmlog"));
  EXPECT_EQ(processed, 0);
  EXPECT_EQ(covered, 500);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0], 1000000 + 500 * 10000) << "the first POSE is the input after the state handed over";
  // A checkpoint's daemon did not see the queue: inputs far older than its state are a source
  // that started over, and are processed (the 0.95 s within max_time_jump are taken as covered).
  const auto [ck_processed, ck_covered, ck_poses] = run(false, path("checkpoint.lcmlog"));
  EXPECT_EQ(ck_covered, 101);
  EXPECT_GE(ck_processed, 390);  // (the last reorder window of them is processed at shutdown)
  EXPECT_LT(ck_poses.front(), 1000000 + 100 * 10000);
}

TEST_F(ReplayTest, AFloodWhileHoldingForAHandOverKeepsTheNewestInputsAndSaysSo) {
  // Inputs queued while a daemon waits for the running one's last POSE (--init-from-bus) used to
  // have no bound: a flood took the memory.
  const std::string out = path("held.lcmlog");
  {
    replay::LogBus bus(out);
    fusion::FusionDaemon daemon(cfg_, bus, fusion::FusionDaemon::Options{true});
    lcmloc::odometry_t o{};
    o.delta_s = 0.0;
    std::vector<uint8_t> buf;
    const int64_t n = 200005;
    for (int64_t k = 0; k < n; ++k) {
      o.utime = 1000000 + k * 10;
      o.seq = k;
      buf.resize(static_cast<std::size_t>(o.getEncodedSize()));
      o.encode(buf.data(), 0, static_cast<int>(buf.size()));
      ASSERT_EQ(bus.dispatch(cfg_.channels.odometry, buf.data(), buf.size(), o.utime), 1);
    }
    EXPECT_EQ(daemon.processed(), 0);
    daemon.release(std::nullopt, "test");
    daemon.shutdown();
    EXPECT_EQ(daemon.processed(), 200000);  // the newest
    bus.close();
  }
  bool said = false;
  for (const auto& ev : readLog(out))
    if (ev.channel == cfg_.channels.status) {
      const auto m = decode<lcmloc::fusion_status_t>(ev);
      if (m.event == "started")
        said = m.detail.find("5 inputs queued while waiting were dropped, the oldest first") != std::string::npos;
    }
  EXPECT_TRUE(said);
}
