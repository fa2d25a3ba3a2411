// Messages decoded into value-initialized locals keep their doubles. Debian's LCM 1.3.1 decodes a
// double by storing its bits through an int64_t pointer (lcm_coretypes.h,
// __double_decode_array); with strict aliasing GCC -O2 may then read the double fields as the
// zeros they were initialized with (a ground_truth_t decoded this way came out (0, 0, 0)). The
// project builds with -fno-strict-aliasing (CMakeLists.txt); this test fails without it.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "lcmloc/bus/transport.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/odometry_t.hpp"

namespace {

volatile double g_base = 1.5;  // not a constant the compiler could fold through encode/decode

template <typename T>
std::vector<uint8_t> encoded(T& m) {
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

struct Fields {
  double a = -1, b = -1, c = -1;
};

/// Decodes into a local that does not outlive the call, as a handler does, and returns its doubles.
Fields truthFields(const std::vector<uint8_t>& buf) {
  lcmloc::ground_truth_t g{};
  if (g.decode(buf.data(), 0, static_cast<int>(buf.size())) < 0) return {};
  return {g.x, g.y, g.heading};
}

Fields flatTruthFields(const std::vector<uint8_t>& buf) {
  lcmloc::ground_truth_t g{};
  if (lcmloc::bus::decodeMessage(g, buf.data(), buf.size()) < 0) return {};
  return {g.x, g.y, g.heading};
}

Fields odometryFields(const std::vector<uint8_t>& buf) {
  lcmloc::odometry_t o{};
  if (lcmloc::bus::decodeMessage(o, buf.data(), buf.size()) < 0) return {};
  return {o.delta_s, o.steering, o.delta_theta};
}

}  // namespace

TEST(LcmDecode, ALocalGroundTruthKeepsItsDoubles) {
  lcmloc::ground_truth_t in{};
  in.utime = 5;
  in.x = g_base;
  in.y = -2.0 * g_base;
  in.heading = g_base / 3.0;
  const auto buf = encoded(in);
  for (const Fields& f : {truthFields(buf), flatTruthFields(buf)}) {
    EXPECT_EQ(f.a, in.x);
    EXPECT_EQ(f.b, in.y);
    EXPECT_EQ(f.c, in.heading);
  }
}

TEST(LcmDecode, ALocalOdometryKeepsItsDoubles) {
  lcmloc::odometry_t in{};
  in.utime = 7;
  in.delta_s = g_base;
  in.steering = -g_base / 10.0;
  in.delta_theta = g_base / 100.0;
  const auto buf = encoded(in);
  const Fields f = odometryFields(buf);
  EXPECT_EQ(f.a, in.delta_s);
  EXPECT_EQ(f.b, in.steering);
  EXPECT_EQ(f.c, in.delta_theta);
}
