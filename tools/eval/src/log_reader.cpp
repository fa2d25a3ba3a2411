#include "lcmloc/eval/log_reader.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/common/convert.hpp"
#include "lcmloc/fault_event_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::eval {
namespace {

constexpr int64_t kEventHeaderBytes = 28;  // sync, event number, utime, channel len, data len

int64_t fileSize(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return -1;
  return static_cast<int64_t>(st.st_size);
}

/// Decodes one payload; records an issue and returns false when it does not decode.
template <typename T>
bool decode(const lcm::LogEvent& ev, T& msg, LogData& out, int64_t offset) {
  if (msg.decode(ev.data, 0, ev.datalen) >= 0) return true;
  out.issues.push_back({out.events_read - 1, offset,
                        "undecodable " + ev.channel + " message (" + std::to_string(ev.datalen) +
                            " bytes, not a " + T::getTypeName() + ")"});
  return false;
}

class Decoder {
 public:
  Decoder(const common::ChannelConfig& ch, LogData& out)
      : ch_(ch), ruler_(ch.magruler.begin(), ch.magruler.end()), out_(out) {}

  void handle(const lcm::LogEvent& ev, int64_t offset) {
    const std::string& c = ev.channel;
    if (c == ch_.ground_truth) truth(ev, offset);
    else if (c == ch_.odometry) odometry(ev, offset);
    else if (ruler_.count(c)) ruler(ev, offset);
    else if (c == ch_.fault_events) fault(ev, offset);
    else if (c == ch_.pose) pose(ev, offset);
    else if (c == ch_.gate) gate(ev, offset);
  }

 private:
  void invalid(int64_t offset, const std::string& what) {
    out_.issues.push_back({out_.events_read - 1, offset, what});
  }
  void truth(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::ground_truth_t m;
    if (!decode(ev, m, out_, offset)) return;
    out_.truth.push_back({m.utime, m.x, m.y, m.heading, m.distance});
  }
  void odometry(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::odometry_t m;
    if (!decode(ev, m, out_, offset)) return;
    ++out_.odometry_messages;
    std::string why;
    auto in = common::toCore(m, &why);
    if (!in) return invalid(offset, "invalid " + ev.channel + " seq " + std::to_string(m.seq) + ": " + why);
    out_.inputs.push_back({ev.channel, m.seq, m.utime, *in});
  }
  void ruler(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::magruler_t m;
    if (!decode(ev, m, out_, offset)) return;
    ++out_.ruler_messages;
    std::string why;
    auto det = common::toCore(m, ev.channel, &why);
    if (!det) {
      if (!why.empty())
        invalid(offset, "invalid " + ev.channel + " seq " + std::to_string(m.seq) + ": " + why);
      return;
    }
    ++out_.ruler_detections;
    out_.inputs.push_back({ev.channel, m.seq, m.utime, *det});
  }
  void fault(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::fault_event_t m;
    if (!decode(ev, m, out_, offset)) return;
    out_.faults.push_back({m.utime, m.kind, m.channel, m.measurement_seq, m.x, m.y, m.lateral_offset});
  }
  void pose(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::pose_t m;
    if (!decode(ev, m, out_, offset)) return;
    if (m.dim < 3 || static_cast<int>(m.state.size()) < 3)
      return invalid(offset, "pose with fewer than 3 states");
    out_.live_poses.push_back({m.utime, m.filter, m.state[0], m.state[1], m.state[2], m.status});
  }
  void gate(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::gate_decision_t m;
    if (!decode(ev, m, out_, offset)) return;
    core::GateDecision d;
    d.utime = m.utime;
    d.sensor = m.sensor;
    d.measurement_seq = m.measurement_seq;
    d.innovation = Eigen::Map<const Eigen::VectorXd>(m.innovation.data(),
                                                     static_cast<Eigen::Index>(m.innovation.size()));
    d.mahalanobis = m.mahalanobis;
    d.gate = m.gate;
    d.accepted = m.accepted;
    d.marker_id = m.marker_id;
    d.reason = m.reason;
    out_.live_decisions.push_back({m.filter, d});
  }

  const common::ChannelConfig& ch_;
  std::set<std::string> ruler_;
  LogData& out_;
};

/// Offset of the next sync word at or after from, or -1 when there is none.
int64_t findSync(FILE* f, int64_t from) {
  static const unsigned char kSync[4] = {0xED, 0xA1, 0xDA, 0x01};
  if (fseeko(f, from, SEEK_SET) != 0) return -1;
  std::vector<unsigned char> buf(1 << 16);
  int64_t base = from;
  size_t keep = 0;  // bytes carried over from the previous chunk
  while (true) {
    const size_t n = fread(buf.data() + keep, 1, buf.size() - keep, f);
    if (n == 0) return -1;
    const size_t len = keep + n;
    for (size_t i = 0; i + 4 <= len; ++i)
      if (std::equal(kSync, kSync + 4, buf.begin() + static_cast<std::ptrdiff_t>(i)))
        return base + static_cast<int64_t>(i);
    keep = std::min<size_t>(3, len);
    std::copy(buf.begin() + static_cast<std::ptrdiff_t>(len - keep),
              buf.begin() + static_cast<std::ptrdiff_t>(len), buf.begin());
    base += static_cast<int64_t>(len - keep);
  }
}

}  // namespace

LogScanner::LogScanner(const std::string& path, std::vector<LogIssue>* issues) : issues_(issues) {
  file_size_ = lcmloc::eval::fileSize(path);
  if (file_size_ < 0) throw std::runtime_error("cannot open log '" + path + "': no such file");
  log_ = std::make_unique<lcm::LogFile>(path, "r");
  if (!log_->good()) throw std::runtime_error("cannot open log '" + path + "' for reading");
  f_ = log_->getFilePtr();
}

LogScanner::~LogScanner() = default;

void LogScanner::closeDamage(int64_t resume_at) {
  if (!dmg_open_) return;
  const int64_t skipped = resume_at - dmg_start_;
  bytes_unreadable_ += skipped;
  std::ostringstream s;
  if (resume_at >= file_size_)
    s << "log ends in a damaged or truncated event: the last " << skipped << " bytes from byte "
      << dmg_start_ << " could not be read (" << events_read_ << " events read before)";
  else
    s << "damaged event at byte " << dmg_start_ << ": skipped " << skipped
      << " bytes, resumed at byte " << resume_at;
  if (issues_) issues_->push_back({dmg_event_index_, dmg_start_, s.str()});
  dmg_open_ = false;
}

const lcm::LogEvent* LogScanner::next() {
  while (true) {
    const int64_t start = ftello(f_);
    const lcm::LogEvent* ev = log_->readNextEvent();
    if (!ev) {
      if (start >= file_size_ && !dmg_open_) return nullptr;  // clean end of file
      if (!dmg_open_) {
        dmg_open_ = true;
        dmg_event_index_ = events_read_;
        dmg_start_ = std::max(start, expected_);
      }
      // Resynchronise on the next sync word after the failed event, if there is one.
      const int64_t next = findSync(f_, start + 1);
      if (next < 0) {
        closeDamage(file_size_);
        expected_ = file_size_;
        return nullptr;
      }
      fseeko(f_, next, SEEK_SET);
      continue;
    }
    const int64_t end = ftello(f_);
    const int64_t event_start =
        end - kEventHeaderBytes - static_cast<int64_t>(ev->channel.size()) - ev->datalen;
    if (event_start > expected_ && !dmg_open_) {
      dmg_open_ = true;
      dmg_event_index_ = events_read_;
      dmg_start_ = expected_;
    }
    closeDamage(event_start);
    expected_ = end;
    event_offset_ = event_start;
    ++events_read_;
    return ev;
  }
}

LogData readLog(const std::string& path, const common::ChannelConfig& channels,
                const std::atomic<bool>* stop) {
  LogData out;
  out.path = path;
  LogScanner scanner(path, &out.issues);
  out.file_size = scanner.fileSize();
  Decoder decoder(channels, out);
  while (!(stop && stop->load())) {
    const lcm::LogEvent* ev = scanner.next();
    if (!ev) break;
    out.events_read = scanner.eventsRead();
    ++out.channel_counts[ev->channel];
    decoder.handle(*ev, scanner.eventOffset());
  }
  out.events_read = scanner.eventsRead();
  out.bytes_unreadable = scanner.bytesUnreadable();
  if (stop && stop->load()) out.interrupted = true;
  out.damaged = out.bytes_unreadable > 0;
  std::stable_sort(out.truth.begin(), out.truth.end(),
                   [](const TruthSample& a, const TruthSample& b) { return a.utime < b.utime; });
  return out;
}

}  // namespace lcmloc::eval
