// Fuzz target: a file given as an .lcmlog to everything that reads one. The scanner event by
// event, each payload of a known type (by its fingerprint) decoded into fields, as to-csv does;
// the evaluation's reader (readTrajectoryLog); lcmloc-log's info, to-csv (a CSV per channel)
// and cut (the whole log, then a time window), which read past damage and write what is intact.
// A log cut by lcmloc-log must then scan without damage.
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "fuzz_util.hpp"
#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/logio/types.hpp"
#include "lcmloc/logtool/log_tool.hpp"

namespace {

using namespace lcmloc;

void scan(const std::string& path) {
  logger::Fields fields;
  logio::scanLog(path, [&](const logio::RawEvent& e) {
    const auto* type = logger::findType(e.data, static_cast<std::size_t>(e.size));
    if (!type) return;
    fields.clear();
    type->fields(e.data, static_cast<std::size_t>(e.size), &fields);
    int64_t seq = 0;
    logger::readSeq(e.data, static_cast<std::size_t>(e.size), &seq);
  });
}

void cutAndRescan(const std::string& path, const std::string& out, const logtool::CutOptions& o) {
  std::remove(out.c_str());
  logtool::cut(path, out, o);
  const auto s = logio::scanLog(out, [](const logio::RawEvent&) {});
  if (s.bytes_unreadable > 0) fuzz::finding("lcmloc-log cut wrote a damaged log");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const bool kQuiet = (fuzz::quiet(), true);
  (void)kQuiet;
  const std::string path = fuzz::writeFile("in.lcmlog", data, size);
  try {
    scan(path);
  } catch (const std::exception& e) {
    fuzz::refused(e);
  }
  try {
    eval::TrajectoryLogOptions opt;
    opt.all_pose_channels = true;
    opt.datum = bus::Datum{};
    eval::readTrajectoryLog(path, opt);
  } catch (const std::exception& e) {
    fuzz::refused(e);
  }
  try {
    logtool::info(path);
  } catch (const std::exception& e) {
    fuzz::refused(e);
  }
  try {
    logtool::toCsv(path, {}, fuzz::freshDir("csv"));
  } catch (const std::exception& e) {
    fuzz::refused(e);
  }
  try {
    const std::string out = (fuzz::scratchDir() / "cut.lcmlog").string();
    cutAndRescan(path, out, {});
    logtool::CutOptions window;
    window.from = 0.05;
    window.to = 0.5;
    cutAndRescan(path, out, window);
  } catch (const std::exception& e) {
    fuzz::refused(e);
  }
  return 0;
}
