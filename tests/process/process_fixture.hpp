#pragma once
// Fixture shared by the tests that run real executables: a temporary directory of the test's own
// (kept when the test fails, for its logs) and a udpm:// URL no other test uses.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "child.hpp"

class ProcessFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("lcmloc_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    url_ = uniqueLcmUrl();
  }
  void TearDown() override {
    if (!HasFailure()) std::filesystem::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string writeFile(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
    return path(name);
  }

  std::filesystem::path dir_;
  std::string url_;
};

/// One event of a log read back whole (event timestamp, channel and encoded message).
struct LogEvent {
  int64_t timestamp = 0;
  std::string channel;
  std::vector<uint8_t> data;
};

/// Every event of a log file, in file order (empty when it cannot be opened).
inline std::vector<LogEvent> readLog(const std::string& file) {
  std::vector<LogEvent> out;
  lcm::LogFile log(file, "r");
  if (!log.good()) return out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.push_back({ev->timestamp, ev->channel, std::vector<uint8_t>(p, p + ev->datalen)});
  }
  return out;
}

/// Decodes one logged message of type T (a failed decode fails the test).
template <typename T>
T decode(const LogEvent& ev) {
  T m;
  EXPECT_GE(m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())), 0) << ev.channel;
  return m;
}
