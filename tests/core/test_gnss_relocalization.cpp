// GNSS filters (tvekf, ukf_gps): re-localization from GPS fixes the gate refused. A start far
// from the configured prior and a kidnapped vehicle are re-localized from fixes that agree with
// each other once carried forward by the dead-reckoned motion; lone outliers and mutually
// inconsistent fixes never move the estimate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/gnss_model.hpp"

using namespace lcmloc::core;

namespace {

const std::vector<std::string> kGnssTypes{"tvekf", "ukf_gps"};

/// The default configuration (config/paper.yaml's fusion.filter: initial pose (0, 0, pi/2),
/// P0 diag 1e-2) of the given type.
FilterConfig defaultConfig(const std::string& type) {
  FilterConfig c;
  c.type = type;
  return c;
}

/// A car-like vehicle: odometry (encoder distance + steering) and IMU (magnetometer heading) at
/// 100 Hz, integrated here by its own loop; GPS fixes from the truth with Gaussian noise.
struct Sim {
  int64_t t = 1'000'000;
  double x = 0, y = 0, th = 0, v = 10.0, psi = 0.0;
  double wheelbase = 2.5;
  double gps_sd = 2.0;
  bool imu = true;
  std::mt19937 rng{7};
  std::normal_distribution<double> noise{0.0, 1.0};

  /// One second of driving into f (and into twin, when given).
  void second(Filter& f, Filter* twin = nullptr) {
    for (int k = 0; k < 100; ++k) {
      t += 10'000;
      const double ds = v * 0.01;
      x += ds * std::cos(th);
      y += ds * std::sin(th);
      th = wrapAngle(th + ds * std::tan(psi) / wheelbase);
      OdometryInput o;
      o.utime = t;
      o.delta_s = ds;
      o.steering = psi;
      o.has_steering = true;
      ImuInput m;
      m.utime = t;
      m.accel = Vec3(0.0, 0.0, 9.81);
      m.mag = gnss::earthFieldBody(th, 0.0, 0.2, -0.4);
      for (Filter* g : {&f, twin}) {
        if (!g) continue;
        g->predict(o);
        if (imu) g->update(m);
      }
    }
  }
  /// A fix of the truth shifted by (dx, dy), with the noise of gps_sd.
  GpsInput fix(double dx = 0.0, double dy = 0.0) {
    GpsInput g;
    g.utime = t;
    g.x = x + dx + gps_sd * noise(rng);
    g.y = y + dy + gps_sd * noise(rng);
    g.position_std = gps_sd;
    return g;
  }
  double error(const Filter& f) const {
    const FilterState s = f.state();
    return std::hypot(s.x[0] - x, s.x[1] - y);
  }
};

/// A filter started at the truth that accepted fixes for `seconds` while driving (its state
/// confirmed by GPS); twin, when given, is built and fed the same.
std::unique_ptr<Filter> settled(const FilterConfig& c, Sim& sim, int seconds, std::unique_ptr<Filter>* twin = nullptr) {
  FilterConfig near = c;
  near.initial_pose = Vec3(sim.x, sim.y, sim.th);
  auto f = makeFilter(near, {});
  if (twin) *twin = makeFilter(near, {});
  for (int s = 0; s < seconds; ++s) {
    sim.second(*f, twin ? twin->get() : nullptr);
    const GpsInput g = sim.fix();
    const auto d = f->update(g);
    EXPECT_TRUE(d && d->accepted) << c.type << " settling fix " << s;
    if (twin) (*twin)->update(g);
  }
  return f;
}

}  // namespace

// (a) The default prior (0, 0) with a sigma of 0.1 m while the vehicle is 110 m away: the first
// fix is refused and kept; the second agrees with it (carried forward by the 10 m driven) and
// the filter re-localizes to within 5 m; the fixes after it are accepted.
TEST(GnssRelocalization, AStartFarFromTheDefaultPriorIsRelocalizedByTheSecondFix) {
  for (const auto& type : kGnssTypes) {
    auto f = makeFilter(defaultConfig(type), {});
    Sim sim;
    sim.x = 90.0;
    sim.y = -63.0;  // 110 m from the prior
    sim.th = M_PI / 2;
    sim.second(*f);
    const GpsInput first = sim.fix();
    auto d = f->update(first);
    ASSERT_TRUE(d);
    EXPECT_EQ(d->reason, "gate") << type;
    EXPECT_FALSE(f->takeRelocalization()) << type << ": one fix is never enough";
    sim.second(*f);
    d = f->update(sim.fix());
    ASSERT_TRUE(d);
    EXPECT_TRUE(d->accepted) << type;
    EXPECT_EQ(d->reason, "relocalized") << type;
    EXPECT_LT(sim.error(*f), 5.0) << type;
    const std::optional<Relocalization> r = f->takeRelocalization();
    ASSERT_TRUE(r) << type;
    EXPECT_EQ(r->fixes, 2) << type;
    EXPECT_EQ(r->first_utime, first.utime) << type;
    EXPECT_GT(r->jump, 100.0) << type;
    EXPECT_FALSE(f->takeRelocalization()) << type << ": reported once";
    for (int s = 0; s < 20; ++s) {
      sim.second(*f);
      d = f->update(sim.fix());
      EXPECT_TRUE(d && d->accepted) << type << " fix " << s + 3;
      EXPECT_LT(sim.error(*f), 5.0) << type << " fix " << s + 3;
    }
    EXPECT_EQ(f->state().status, FilterStatus::Ok) << type;
  }
}

// (a) as the live gpsd test feeds it: fixes only (no odometry, no IMU), the vehicle moving east
// at 5 m/s while the prior says north; the fixes carry a sigma of 5 m.
TEST(GnssRelocalization, GpsOnlyStartIsRelocalizedByTheSecondFix) {
  for (const auto& type : kGnssTypes) {
    auto f = makeFilter(defaultConfig(type), {});
    std::mt19937 rng(3);
    std::normal_distribution<double> n(0.0, 1.0);
    auto fixAt = [&](int k) {
      GpsInput g;
      g.utime = 1'000'000 + k * 1'000'000LL;
      g.x = 100.0 + 5.0 * k + 2.0 * n(rng);
      g.y = 50.0 + 2.0 * n(rng);
      g.position_std = 5.0;
      return g;
    };
    EXPECT_EQ(f->update(fixAt(0))->reason, "gate") << type;
    EXPECT_EQ(f->update(fixAt(1))->reason, "relocalized") << type;
    FilterState s = f->state();
    EXPECT_LT(std::hypot(s.x[0] - 105.0, s.x[1] - 50.0), 5.0) << type;
    // Without odometry the filter's motion model is the position random walk (gnss.position_rw,
    // 0.1 m/sqrt(s)): it lags a vehicle that moves, its gate refuses the fixes once the lag is
    // large, and the third refused fix that agrees re-localizes it (never more than two refused
    // in a row).
    int refused_in_a_row = 0, most_in_a_row = 0, relocalized = 0;
    for (int k = 2; k < 30; ++k) {
      const auto d = f->update(fixAt(k));
      refused_in_a_row = d->reason == "gate" ? refused_in_a_row + 1 : 0;
      most_in_a_row = std::max(most_in_a_row, refused_in_a_row);
      relocalized += d->reason == "relocalized";
      s = f->state();
      // lag at most the gate's reach (sqrt(9.21 (5^2 + 5^2)) = 21.5 m) plus two refused fixes' 10 m
      EXPECT_LT(std::hypot(s.x[0] - 100.0 - 5.0 * k, s.x[1] - 50.0), 32.0) << type << " fix " << k;
    }
    EXPECT_LE(most_in_a_row, 2) << type;
    EXPECT_GE(relocalized, 1) << type;
  }
}

// (b) A kidnapped vehicle: after 30 s on track, the truth jumps 40 m sideways (the odometry does
// not see it). The fixes after the jump are refused, the third re-localizes (a state confirmed by
// fixes takes three), and the estimate is on track again.
TEST(GnssRelocalization, AKidnappedVehicleIsRelocalizedWithinThreeFixes) {
  for (const auto& type : kGnssTypes) {
    Sim sim;
    auto f = settled(defaultConfig(type), sim, 30);
    sim.y += 40.0;
    int relocalized_at = 0;
    for (int k = 1; k <= 10 && relocalized_at == 0; ++k) {
      const FilterState before = f->state();
      sim.second(*f);
      const auto d = f->update(sim.fix());
      ASSERT_TRUE(d);
      if (d->reason == "relocalized") {
        relocalized_at = k;
      } else {
        EXPECT_EQ(d->reason, "gate") << type << " fix " << k;
      }
    }
    EXPECT_EQ(relocalized_at, 3) << type;
    const auto r = f->takeRelocalization();
    ASSERT_TRUE(r) << type;
    EXPECT_EQ(r->fixes, 3) << type;
    EXPECT_NEAR(r->jump, 40.0, 8.0) << type;
    EXPECT_LT(r->spread, 9.0) << type;  // the 2-dof gate of two fixes' variance: sqrt(9.21 * 2 * 2^2)
    EXPECT_LT(sim.error(*f), 5.0) << type;
    for (int s = 0; s < 10; ++s) {
      sim.second(*f);
      EXPECT_TRUE(f->update(sim.fix())->accepted) << type;
    }
    EXPECT_LT(sim.error(*f), 3.0) << type;
  }
}

// (c) 60 s of fixes where every 5th is a wild outlier (50-150 m off in turning directions): each
// is refused, none re-localizes, and the estimate is exactly that of a twin given only the good
// fixes. Then 20 s of nothing but mutually inconsistent fixes (60 m off, each in another
// direction): refused, a lock-out without inflation, no re-localization; the estimate
// dead-reckons as the twin does.
TEST(GnssRelocalization, OutliersAndInconsistentFixesNeverRelocalize) {
  for (const auto& type : kGnssTypes) {
    Sim sim;
    sim.psi = 0.02;  // a wide circle
    std::unique_ptr<Filter> twin;
    auto f = settled(defaultConfig(type), sim, 10, &twin);
    double worst = 0.0;
    for (int k = 1; k <= 60; ++k) {
      sim.second(*f, twin.get());
      if (k % 5 == 0) {
        const double a = 2.4 * k, r = 50.0 + 100.0 * ((k / 5) % 3) / 2.0;
        const auto d = f->update(sim.fix(r * std::cos(a), r * std::sin(a)));
        EXPECT_EQ(d->reason, "gate") << type << " outlier " << k;
      } else {
        const GpsInput g = sim.fix();
        EXPECT_TRUE(f->update(g)->accepted) << type << " fix " << k;
        twin->update(g);
      }
      EXPECT_FALSE(f->takeRelocalization()) << type << " at " << k;
      worst = std::max(worst, (f->state().x - twin->state().x).norm());
      EXPECT_LT(sim.error(*f), 3.0 * sim.gps_sd) << type << " at " << k;
    }
    EXPECT_LT(worst, 1e-9) << type;
    for (int k = 0; k < 20; ++k) {
      sim.second(*f, twin.get());
      const double a = k * 2.39996;  // the golden angle: never two directions alike in a window
      const auto d = f->update(sim.fix(60.0 * std::cos(a), 60.0 * std::sin(a)));
      EXPECT_EQ(d->reason, "gate") << type << " inconsistent " << k;
      EXPECT_FALSE(f->takeRelocalization()) << type << " inconsistent " << k;
    }
    const FilterState s = f->state(), ts = twin->state();
    EXPECT_EQ(s.status, FilterStatus::Lockout) << type;
    EXPECT_LT((s.x - ts.x).norm(), 1e-9) << type;
    EXPECT_NEAR(s.P(0, 0), ts.P(0, 0), 1e-9 * ts.P(0, 0)) << type << ": no inflation";
    EXPECT_LT(sim.error(*f), 3.0 * sim.gps_sd) << type;
  }
}

// (d) The rule does not need the vehicle to stand still: a kidnapped vehicle driving a curve at
// 15 m/s with fixes of 0.5 m sigma, 15 m apart, is re-localized by the third fix (without the
// dead-reckoned motion they would be 15 m apart, 20 sigma); and a heading 0.6 rad off (no
// magnetometer) comes back from the chord of the fixes.
TEST(GnssRelocalization, MovingFixesAgreeAfterMotionCompensationAndGiveTheHeading) {
  for (const auto& type : kGnssTypes) {
    Sim sim;
    sim.v = 15.0;
    sim.psi = 0.03;
    sim.gps_sd = 0.5;
    FilterConfig c = defaultConfig(type);
    c.gnss.use_magnetometer = false;
    sim.imu = false;
    auto f = settled(c, sim, 10);
    sim.x += 30.0;
    sim.y -= 20.0;
    sim.th = wrapAngle(sim.th + 0.6);
    int k = 1;
    for (; k <= 6; ++k) {
      sim.second(*f);
      if (f->update(sim.fix())->reason == "relocalized") break;
    }
    EXPECT_LE(k, 3) << type;
    const auto r = f->takeRelocalization();
    ASSERT_TRUE(r) << type;
    EXPECT_GE(r->fixes, 3) << type;
    EXPECT_LT(r->spread, 3.0) << type;
    EXPECT_TRUE(r->heading_from_chord) << type;
    EXPECT_NEAR(r->heading_change, 0.6, 0.15) << type;
    EXPECT_LT(std::abs(wrapAngle(f->state().x[2] - sim.th)), 0.15) << type;
    EXPECT_LT(sim.error(*f), 2.0) << type;
    // tvekf has nothing that corrects its heading here (no magnetometer, no course aid): the
    // heading error left by the chord lets a fix of 0.5 m sigma fail the gate now and then.
    int accepted = 0;
    for (int s = 0; s < 10; ++s) {
      sim.second(*f);
      accepted += f->update(sim.fix())->accepted;
    }
    EXPECT_GE(accepted, 8) << type;
    EXPECT_LT(sim.error(*f), 2.0) << type;
  }
}

// The engine reports each re-localization once, as a "relocalized" event with its evidence.
TEST(GnssRelocalization, TheEngineReportsTheEvidence) {
  EngineConfig ec;
  ec.filter = defaultConfig("tvekf");
  std::vector<EngineEvent> events;
  EngineOutputs out;
  out.on_event = [&](const EngineEvent& e) { events.push_back(e); };
  FusionEngine engine(ec, {}, out);
  for (int k = 0; k < 5; ++k) {
    const int64_t t = 1'000'000 + k * 1'000'000LL;
    GpsInput g;
    g.utime = t;
    g.x = 80.0 + 0.5 * (k % 2);
    g.y = 10.0;
    g.position_std = 2.0;
    engine.push({"GPS", k, t, g});
  }
  engine.flush();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, EventKind::Relocalized);
  EXPECT_STREQ(eventName(events[0].kind), "relocalized");
  const auto& e = std::get<events::Relocalized>(events[0].fields);
  EXPECT_EQ(e.filter, "tvekf");
  EXPECT_EQ(e.input.seq, 1);
  EXPECT_EQ(e.evidence.fixes, 2);
  EXPECT_EQ(e.evidence.first_utime, 1'000'000);
  EXPECT_NEAR(e.evidence.spread, 0.5, 1e-9);
  EXPECT_NEAR(e.evidence.jump, std::hypot(80.5, 10.0), 1e-6);
  const std::string text = eventText(events[0]);
  EXPECT_NE(text.find("2 GPS fixes agree within 0.50 m"), std::string::npos) << text;
  EXPECT_NEAR(engine.activeState().x[0], 80.0, 1.0);
}
