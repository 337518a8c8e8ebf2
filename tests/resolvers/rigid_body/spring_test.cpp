// Springs with dampers (resolvers/rigid_body/rigid_body_from_springs.*)
// against their closed forms, through the real world and plugins: a mass on a
// spring swings with period 2 pi sqrt(m / k), a damped one decays as
// exp(-c t / 2m), two parts swing with their reduced mass about a centre of
// mass that stays put, a spring at a point turns the part, and a spring too
// stiff for the step is refused by name. Each test prints its figures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "resolvers/rigid_body/rigid_body_from_springs.hpp"
#include "runtime/energy_ledger.hpp"
#include "runtime/error.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

constexpr double kPi = std::numbers::pi;

WorldDef no_gravity(double dt) {
  WorldDef def;
  def.dt = dt;
  def.settings["gravity.uniform"].set("g", Vec3{0, 0, 0});
  return def;
}

ObjectId add_spring(World& w, ObjectId a, Vec3 anchor_a, ObjectId b, Vec3 anchor_b, double k,
                    double rest, double c, const std::string& name = "spring") {
  const ObjectId s = w.create(name);
  w.set(s, "spring_a", a);
  if (!b.is_null()) w.set(s, "spring_b", b);
  w.set(s, "spring_anchor_a", anchor_a);
  w.set(s, "spring_anchor_b", anchor_b);
  w.set(s, "spring_stiffness", k);
  w.set(s, "spring_rest_length", rest);
  w.set(s, "spring_damping", c);
  w.check(s);
  return s;
}

/// Times of the upward zero crossings of `x`, linearly interpolated.
std::vector<double> up_crossings(const std::vector<double>& x, double dt) {
  std::vector<double> t;
  for (std::size_t i = 1; i < x.size(); ++i)
    if (x[i - 1] < 0 && x[i] >= 0) t.push_back(dt * (double(i - 1) + x[i - 1] / (x[i - 1] - x[i])));
  return t;
}

/// The mean period between the first and last upward crossings.
double mean_period(const std::vector<double>& crossings) {
  if (crossings.size() < 2) return 0;
  return (crossings.back() - crossings.front()) / double(crossings.size() - 1);
}

/// A ball of mass m on a spring to the board, stretched `stretch` past its
/// rest length along x and let go; returns its stretch after every step.
std::vector<double> ball_on_spring(double dt, double m, double k, double c, double seconds) {
  Sim s(no_gravity(dt));
  const double rest = 0.5, stretch = 0.1;
  const ObjectId ball = add_sphere(*s, {rest + stretch, 0, 0}, 0.02, m, "ball");
  add_spring(*s, ball, {0, 0, 0}, {}, {0, 0, 0}, k, rest, c);
  std::vector<double> x{stretch};
  const auto n = std::uint64_t(std::llround(seconds / dt));
  for (std::uint64_t i = 0; i < n; ++i) {
    s->step();
    x.push_back(length(s.position(ball)) - rest);
  }
  return x;
}

TEST(Spring, AMassOnASpringSwingsWithPeriodTwoPiSqrtMOverKAtEveryStep) {
  // m = 0.5 kg, k = 50 N/m: w = 10 rad/s, T = 0.6283 s; h w from 0.17 to 0.01.
  const double m = 0.5, k = 50, period = 2 * kPi * std::sqrt(m / k);
  double previous = 1;
  for (double dt : {1.0 / 60, 1.0 / 240, 1.0 / 960}) {
    const std::vector<double> x = ball_on_spring(dt, m, k, 0, 8 * period);
    const double measured = mean_period(up_crossings(x, dt));
    double peak = 0;
    for (double v : x) peak = std::max(peak, std::abs(v));
    const double error = std::abs(measured / period - 1);
    std::printf("h = 1/%.0f s (h w = %.3f): period %.6f s against %.6f s (%.3g), peak %.5f m\n",
                1 / dt, dt * std::sqrt(k / m), measured, period, error, peak);
    EXPECT_LT(error, 2e-3) << "dt 1/" << 1 / dt;
    EXPECT_NEAR(peak, 0.1, 0.1 * 0.02) << "an undamped spring keeps its amplitude";
    EXPECT_LE(error, previous) << "the error falls with the step";
    previous = error;
  }
}

TEST(Spring, ADampedSpringDecaysAsExpMinusCTOverTwoM) {
  // c = 1 N s/m on 0.5 kg: the envelope falls as exp(-t) (zeta = 0.1), and the
  // swing is at w_d = sqrt(k/m - (c/2m)^2).
  const double m = 0.5, k = 50, c = 1, gamma = c / m;
  const double wd = std::sqrt(k / m - gamma * gamma / 4);
  // The explicit damper also shifts the swing's period, at first order in h
  // (1 % at 1/60 s, 0.2 % at 1/240 s): both errors fall with the step.
  double previous = 1, previous_period = 1;
  for (double dt : {1.0 / 60, 1.0 / 240, 1.0 / 960}) {
    const std::vector<double> x = ball_on_spring(dt, m, k, c, 4 * 2 * kPi / wd);
    // The peaks (local maxima) and their times.
    std::vector<double> peak, when;
    for (std::size_t i = 1; i + 1 < x.size(); ++i)
      if (x[i] > x[i - 1] && x[i] >= x[i + 1] && x[i] > 0)
        peak.push_back(x[i]), when.push_back(dt * double(i));
    ASSERT_GE(peak.size(), 3u);
    const double rate = std::log(peak.front() / peak.back()) / (when.back() - when.front());
    const double error = std::abs(rate / (gamma / 2) - 1);
    const double period = mean_period(up_crossings(x, dt));
    std::printf(
        "h = 1/%.0f s: decay rate %.5f /s against %.5f /s (%.3g); period %.5f s against %.5f s\n",
        1 / dt, rate, gamma / 2, error, period, 2 * kPi / wd);
    EXPECT_LT(error, 0.03) << "dt 1/" << 1 / dt;
    const double period_error = std::abs(period * wd / (2 * kPi) - 1);
    EXPECT_LT(period_error, 0.015) << "dt 1/" << 1 / dt;
    EXPECT_LE(error, previous);
    EXPECT_LE(period_error, previous_period);
    previous = error, previous_period = period_error;
  }
}

TEST(Spring, TwoPartsSwingWithTheirReducedMassAboutACentreOfMassThatStaysPut) {
  // 1 kg and 3 kg: mu = 0.75 kg, k = 75 N/m, w = 10 rad/s.
  const double dt = 1.0 / 240, k = 75, mu = 0.75, rest = 0.4;
  Sim s(no_gravity(dt));
  const ObjectId a = add_sphere(*s, {0.45, 0, 0}, 0.02, 1.0, "light");
  const ObjectId b = add_sphere(*s, {0, 0, 0}, 0.02, 3.0, "heavy");
  add_spring(*s, a, {}, b, {}, k, rest, 0);
  const double cm0 = (1.0 * 0.45 + 3.0 * 0) / 4;
  std::vector<double> stretch;
  double drift = 0;
  for (int i = 0; i < 240 * 4; ++i) {
    s->step();
    const Vec3 pa = s.position(a), pb = s.position(b);
    stretch.push_back(pa.x - pb.x - rest);
    drift = std::max(drift, std::abs((1.0 * pa.x + 3.0 * pb.x) / 4 - cm0));
  }
  const double period = mean_period(up_crossings(stretch, dt)), exact = 2 * kPi * std::sqrt(mu / k);
  std::printf("two parts: period %.6f s against %.6f s; centre of mass moved %.3g m\n", period,
              exact, drift);
  EXPECT_NEAR(period, exact, exact * 1e-3);
  EXPECT_LT(drift, 1e-9);
}

TEST(Spring, ASpringAtAPointOfAPartTurnsIt) {
  // A bar on an axle at its centre, pulled down at its +x end: it turns
  // clockwise (angular velocity -z), and its centre stays on the axle.
  Sim s(no_gravity(1.0 / 240));
  const ObjectId bar = add_box(*s, {0, 0, 0}, {1, 0.04, 0.04}, 1.0, {}, "bar");
  add_hinge(*s, bar, {}, {0, 0, 0});
  add_spring(*s, bar, {0.5, 0, 0}, {}, {0.5, -0.5, 0}, 20, 0.3, 0);
  s.run_for(0.1);
  const double wz = std::get<Vec3>(s->get(bar, "angular_velocity")).z;
  std::printf("bar: angular velocity %.4f rad/s after 0.1 s\n", wz);
  EXPECT_LT(wz, -0.1);
  EXPECT_LT(length(s.position(bar)), 1e-6);
}

TEST(Spring, ASpringTooStiffForTheStepIsRefusedByNameWithItsFigures) {
  // 10 g on 1000 N/m: w = 316 rad/s; at 1/240 s, (h w)^2 = 1.74 > 1: refused.
  // At 1/960 s, (h w)^2 = 0.11: accepted, and it swings at its period.
  {
    Sim s(no_gravity(1.0 / 240));
    const ObjectId ball = add_sphere(*s, {0.6, 0, 0}, 0.01, 0.01, "bead");
    try {
      add_spring(*s, ball, {}, {}, {}, 1000, 0.5, 0, "stiff_spring");
      FAIL() << "a spring past the limit was accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      std::printf("refused: %s\n", what.c_str());
      EXPECT_NE(what.find("stiff_spring"), std::string::npos) << what;
      EXPECT_NE(what.find("1.736"), std::string::npos) << what;  // (h w)^2
      EXPECT_NE(what.find("smaller step"), std::string::npos) << what;
    }
    // The refused spring is still there (the check refuses, it does not
    // remove): the step refuses it as well, by name.
    try {
      s->step();
      FAIL() << "a step used a spring past the limit";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("stiff_spring"), std::string::npos) << e.what();
    }
  }
  {
    Sim s(no_gravity(1.0 / 960));
    const ObjectId ball = add_sphere(*s, {0.6, 0, 0}, 0.01, 0.01, "bead");
    const ObjectId sp = add_spring(*s, ball, {}, {}, {}, 1000, 0.5, 0, "stiff_spring");
    EXPECT_NEAR(rigid::spring_stability(*s, sp).figure, std::pow(std::sqrt(1e5) / 960, 2), 1e-9);
    s.run_for(0.2);
    EXPECT_LT(std::abs(length(s.position(ball)) - 0.5), 0.1 * 1.02);
  }
  {
    // Damping alone can break it too: 2 h c / m = 2.08 at 1/240 s.
    Sim s(no_gravity(1.0 / 240));
    const ObjectId ball = add_sphere(*s, {0.6, 0, 0}, 0.01, 0.01, "bead");
    EXPECT_THROW(add_spring(*s, ball, {}, {}, {}, 1, 0.5, 2.5, "sticky"), InputError);
  }
}

// --- energy books -------------------------------------------------------------

struct SpringBooks {
  double moved = 0, fraction = 0, heat = 0, integration = 0, stored = 0, kinetic = 0, apart = 0;
  double rigid_integration = 0;  ///< the rigid body's own integration sink
};

/// Runs `seconds` with the ledger recording after every step.
SpringBooks books_of(Sim& s, double seconds) {
  EnergyLedger books;
  s->start();
  books.record(*s);
  const auto n = std::uint64_t(std::llround(seconds / s->dt()));
  for (std::uint64_t i = 0; i < n; ++i) {
    s->step();
    books.record(*s);
  }
  auto total = [&](const char* stage, const char* name) {
    const EnergyAccount* a = books.find(stage, name);
    return a ? a->total : std::nan("");
  };
  SpringBooks r;
  r.moved = books.total().moved;
  r.fraction = books.total().fraction();
  r.heat = total("rigid_body_from_springs", "damper heat");
  r.integration = total("rigid_body_from_springs", "integration (explicit spring force)");
  r.stored = total("rigid_body_from_springs", "spring energy");
  r.kinetic = total("rigid_body", "kinetic energy");
  r.rigid_integration = total("rigid_body", "integration and position corrections");
  r.apart = total("rigid_body_from_springs", "springs") + total("rigid_body", "springs");
  return r;
}

TEST(Spring, EnergyBooksTheDamperHeatAndCloseAsTheStepShrinks) {
  // 0.5 kg on 50 N/m stretched 0.1 m: 0.25 J in the spring. With c = 0.5 N s/m
  // the swing dies as exp(-t) in energy: after 10 s all but 5e-5 of it is
  // damper heat. The explicit force's share, -(k h / 2c) E0 summed over the
  // swing, falls as the step; the rigid body's semi-implicit step books the
  // same amount the other way (the scheme keeps a nearby energy): the two
  // cancel, and the books close to rounding.
  const double m = 0.5, k = 50, c = 0.5, e0 = 0.5 * k * 0.1 * 0.1;
  double last_integration = 0;
  for (double dt : {1.0 / 60, 1.0 / 240, 1.0 / 960}) {
    Sim s(no_gravity(dt));
    const ObjectId ball = add_sphere(*s, {0.6, 0, 0}, 0.02, m, "ball");
    add_spring(*s, ball, {}, {}, {}, k, 0.5, c);
    const SpringBooks b = books_of(s, 10);
    std::printf(
        "damped spring at 1/%.0f s: moved %.4f J, damper heat %.5f J (of %.3f J), integration "
        "%+.2e J (the rigid body's %+.2e J), stored %+.5f J, kinetic %+.2e J, the transfer's "
        "sides apart %.1e J, residue %.1e of moved\n",
        1 / dt, b.moved, b.heat, e0, b.integration, b.rigid_integration, b.stored, b.kinetic,
        b.apart, b.fraction);
    EXPECT_NEAR(b.heat, e0, 0.01 * e0);
    EXPECT_NEAR(b.stored, -e0, 1e-3 * e0);  // the spring ends (nearly) at rest
    // The two sides of the spring's work on the ball agree: a ball moves by h v'.
    EXPECT_LT(std::abs(b.apart), 1e-9);
    EXPECT_NEAR(b.integration, -k * dt / (2 * c) * e0, 0.03 * k * dt / (2 * c) * e0);
    EXPECT_LT(std::abs(b.integration + b.rigid_integration), 0.01 * std::abs(b.integration));
    if (last_integration != 0) EXPECT_NEAR(last_integration / b.integration, 4, 0.1);
    last_integration = b.integration;
    EXPECT_LT(b.fraction, 1e-3);
  }
}

TEST(Spring, EnergyBooksCloseForASpringThatTurnsAHingedBar) {
  // The spring at the tip of a hinged bar, no damper: energy swings between
  // the spring and the bar's turning; the books close.
  Sim s(no_gravity(1.0 / 240));
  const ObjectId bar = add_box(*s, {0, 0, 0}, {1, 0.04, 0.04}, 1.0, {}, "bar");
  add_hinge(*s, bar, {}, {0, 0, 0});
  add_spring(*s, bar, {0.5, 0, 0}, {}, {0.5, -0.5, 0}, 20, 0.3, 0);
  const SpringBooks b = books_of(s, 5);
  std::printf(
      "spring on a hinged bar, 5 s at 1/240 s: moved %.4f J, integration %+.2e J, the transfer's "
      "sides apart %.1e J, residue %.1e of moved\n",
      b.moved, b.integration, b.apart, b.fraction);
  EXPECT_GT(b.moved, 0.1);
  EXPECT_EQ(b.heat, 0);
  EXPECT_LT(std::abs(b.apart), 0.01 * b.moved);
  EXPECT_LT(b.fraction, 0.01);
}

}  // namespace
}  // namespace alloy::scenes
