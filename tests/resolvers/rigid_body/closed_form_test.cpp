// The closed-form cases of issue 12, through the real world and plugins (the
// scenes are the work-precision benchmark's, tests/scenes/analytic_scenes):
// each meets its bound at the default step (1/240 s) and converges as the
// step falls, at 1/240, 1/480 and 1/960 s. Each test prints its figures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "tests/scenes/analytic_scenes.hpp"

namespace alloy::scenes::analytic {
namespace {

constexpr double kPi = std::numbers::pi;
const std::vector<double> kSteps = {1.0 / 240, 1.0 / 480, 1.0 / 960};

/// Least-squares slope of log(error) against log(dt).
double observed_order(const std::vector<double>& dts, const std::vector<double>& errors) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = double(dts.size());
  for (std::size_t i = 0; i < dts.size(); ++i) {
    const double x = std::log(dts[i]), y = std::log(errors[i]);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

/// Runs `run` at each step, prints `what` of each, and checks the bound at
/// the first step and the convergence: an observed order of at least 1 (to
/// 1 %: a first-order error with a small second-order part of the other sign,
/// as the bounce's, fits a slope of 0.996), or every error at rounding level
/// (`floor`), where an order means nothing.
void expect_converges(const char* name, const std::vector<double>& dts,
                      const std::function<double(double)>& what, double bound, double floor) {
  std::vector<double> e;
  for (double dt : dts) {
    e.push_back(what(dt));
    std::printf("%s at 1/%.0f s: %.3g\n", name, 1 / dt, e.back());
  }
  EXPECT_LE(e.front(), bound) << name << " at 1/" << 1 / dts.front() << " s";
  bool all_exact = true;
  for (double x : e) {
    EXPECT_TRUE(std::isfinite(x)) << name;
    all_exact = all_exact && x <= floor;
  }
  if (all_exact) return;
  const double order = observed_order(dts, e);
  std::printf("%s: observed order %.2f\n", name, order);
  EXPECT_GE(order, 0.99) << name;
}

TEST(ClosedForm, ElasticPairOfEqualMassesSwapsVelocities) {
  // v' = (0, 1) m/s within 1e-6 at every step from 1/60 to 1/1920 s.
  const std::vector<double> all = {1.0 / 60,  1.0 / 120, 1.0 / 240,
                                   1.0 / 480, 1.0 / 960, 1.0 / 1920};
  expect_converges(
      "elastic pair 1:1, |v - v_exact| (m/s)", all,
      [](double dt) { return run_elastic_pair(dt, Method{}, 1.0).error; }, 1e-6, 1e-6);
}

TEST(ClosedForm, ElasticPairThreeToOne) {
  // 3 kg onto 1 kg at 1 m/s: v' = (0.5, 1.5) m/s.
  const std::vector<double> all = {1.0 / 60,  1.0 / 120, 1.0 / 240,
                                   1.0 / 480, 1.0 / 960, 1.0 / 1920};
  expect_converges(
      "elastic pair 3:1, |v - v_exact| (m/s)", all,
      [](double dt) { return run_elastic_pair(dt, Method{}, 3.0).error; }, 1e-6, 1e-6);
}

TEST(ClosedForm, NewtonsCradlePassesTheMomentumToTheLastBall) {
  expect_converges(
      "cradle, |v - (0,0,0,0,1)| (m/s)", kSteps,
      [](double dt) { return run_cradle(dt, Method{}).error; }, 1e-6, 1e-6);
  const Result r = run_cradle(1.0 / 240, Method{});
  std::printf("cradle: last ball %.9f m/s, kinetic energy drift %.3g\n", r.measured,
              r.energy_drift);
  EXPECT_LT(r.energy_drift, 1e-6);
}

TEST(ClosedForm, BounceReboundsToRestitutionSquared) {
  // The rebound's height ratio converges to e^2 at first order. What is left
  // at 1/240 s (2.7 % for e = 0.5) is the flight's own semi-implicit Euler
  // error, as in free fall: the ball lands early by h u / 2 and the rebound
  // tops out low by h e u / 2 (u = sqrt(2 g h0), the landing speed), so the
  // ratio is e^2 (1 - h u / (2 h0)) - h e u / (2 h0). The collision adds
  // less than 3e-4 of its own to that.
  for (double e : {0.5, 0.9}) {
    const std::string name = "bounce e=" + std::to_string(e).substr(0, 3) + ", |h1/h0 / e^2 - 1|";
    expect_converges(
        name.c_str(), kSteps, [e](double dt) { return run_bounce(dt, Method{}, e).error; }, 0.03,
        1e-6);
    for (double dt : kSteps) {
      const double u = std::sqrt(2 * 9.81 * 1.0);
      const double flight = e * e * (1 - dt * u / 2) - dt * e * u / 2;
      const Result r = run_bounce(dt, Method{}, e);
      std::printf("bounce e=%.1f at 1/%.0f s: ratio %.6f, e^2 %.4f, with the flight's error %.6f\n",
                  e, 1 / dt, r.measured, e * e, flight);
      EXPECT_NEAR(r.measured / flight, 1, 3e-4) << "e " << e << " dt " << dt;
    }
  }
}

// Joints at the default step (issue 12, items 3 and 5): the hinges' position
// projection (resolvers/rigid_body/joint_projection.hpp) holds them. Before
// it, at 1/240 s: the lever at 90 degrees ran 2.0 % short with its hinge
// stretched 4.9 %, at 170 degrees 47 % short; the bar at 170 degrees 5.8 %
// short (the error reduction took 0.6 % of the energy a period); the 1000:1
// chain came apart. The bounds below are the issue's.
constexpr double kStretchBound = 1e-3;  // 0.1 % of the length
constexpr double kPeriodBound = 5e-3;   // 0.5 % at 170 degrees
constexpr double kDriftBound = 1e-3;    // 0.1 % of the swing's energy a period
// A hinge held to rounding: 1e-9 of the length (measured: 1e-11 and less).
constexpr double kHeld = 1e-9;

TEST(ClosedForm, SmallBallOnALongLeverHoldsItsLength) {
  for (double deg : {90.0, 170.0}) {
    const double th = deg * kPi / 180;
    const std::string name = "lever " + std::to_string(int(deg)) + " deg";
    expect_converges((name + ", stretch").c_str(), kSteps,
                     [th](double dt) { return run_swing(dt, Method{}, true, th).stretch; },
                     kStretchBound, kHeld);
    expect_converges((name + ", period error").c_str(), kSteps,
                     [th](double dt) { return run_swing(dt, Method{}, true, th).error; },
                     kPeriodBound, 1e-9);
    expect_converges((name + ", energy drift per period").c_str(), kSteps,
                     [th](double dt) { return run_swing(dt, Method{}, true, th).energy_drift; },
                     kDriftBound, 1e-6);
  }
}

TEST(ClosedForm, BarPendulumAt170Degrees) {
  const double th = 170 * kPi / 180;
  expect_converges(
      "bar 170 deg, period error", kSteps,
      [th](double dt) { return run_swing(dt, Method{}, false, th).error; }, kPeriodBound, 1e-9);
  expect_converges(
      "bar 170 deg, energy drift per period", kSteps,
      [th](double dt) { return run_swing(dt, Method{}, false, th).energy_drift; }, kDriftBound,
      1e-6);
  // The energy's O(h) swing within a period is the semi-implicit Euler
  // step's (it conserves a nearby energy): first order, no drift.
  expect_converges(
      "bar 170 deg, energy swing within the run", kSteps,
      [th](double dt) { return run_swing(dt, Method{}, false, th).energy_wobble; }, 0.01, 1e-9);
}

TEST(ClosedForm, ChainAtAThousandToOneHolds) {
  // The links' fast transverse mode (about 1000 rad/s under the ball's
  // weight) is past what SHAKE's explicit step holds at 1/240 and 1/480 s;
  // there the projection falls back to the end-of-step directions
  // (joint_projection.hpp), which holds the chain to 5e-5 at 1/240 s.
  expect_converges(
      "chain 1000:1, stretch", kSteps,
      [](double dt) { return run_heavy_chain(dt, Method{}).stretch; }, kStretchBound, kHeld);
  // Its energy is not the issue's: where the fallback acts (1/240 and 1/480
  // s) it damps the links' fast mode, and with it the swing, by O(h).
  // Measured over 3 s: 10 % of the swing at 1/240 s, 3.1 % at 1/480, 0.22 %
  // at 1/960. Held here: it converges, and 0.12 guards the figure.
  expect_converges(
      "chain 1000:1, energy change of the swing", kSteps,
      [](double dt) { return run_heavy_chain(dt, Method{}).energy_drift; }, 0.12, 1e-9);
}

TEST(ClosedForm, WithoutTheProjectionTheLeverStretches) {
  // The setting joint_projection = false gives ODE's hinges alone: the
  // figures of before, so that the tests above measure the projection.
  Method ode_only;
  ode_only.joint_projection = false;
  const Result r = run_swing(1.0 / 240, ode_only, true, kPi / 2);
  std::printf("lever 90 deg without the projection: stretch %.3g, period error %.3g\n", r.stretch,
              r.error);
  EXPECT_GT(r.stretch, 0.01);
  EXPECT_GT(r.error, 0.01);
}

TEST(ClosedForm, TumblingBoxKeepsEnergyAndAngularMomentum) {
  expect_converges(
      "tumbling box 10 s, energy drift", kSteps,
      [](double dt) { return run_tumbling_box(dt, Method{}, 10.0).energy_drift; }, 0.001, 1e-9);
  expect_converges(
      "tumbling box 10 s, angular momentum drift", kSteps,
      [](double dt) { return run_tumbling_box(dt, Method{}, 10.0).momentum_drift; }, 0.001, 1e-9);
}

TEST(ClosedForm, EllipticIntegralAgreesWithItsSeries) {
  // K(0) = pi / 2; K(sin 45 deg) = 1.854074677...; the lever's periods as
  // the issue gives them. The bar's is 3.99634 s with its 4 cm width in the
  // inertia (the 3.99575 s leaves out part of it).
  EXPECT_NEAR(elliptic_k(0), kPi / 2, 1e-15);
  EXPECT_NEAR(elliptic_k(std::sin(kPi / 4)), 1.8540746773013719, 1e-13);
  EXPECT_NEAR(swing_period(true, kPi / 2), 2.36803, 1e-5);
  EXPECT_NEAR(swing_period(true, 170 * kPi / 180), 4.89392, 1e-5);
  EXPECT_NEAR(swing_period(false, 170 * kPi / 180), 3.99634, 1e-5);
}

}  // namespace
}  // namespace alloy::scenes::analytic

// --- rolling (issue 12, the kit's cylinder) ----------------------------------------------

namespace alloy::scenes::analytic {
namespace {

TEST(ClosedForm, DiskRollsDownASlopeAtTwoThirdsOfGSinTheta) {
  // A disk (shape cylinder) rolls at 2/3 g sin(theta), a ball at 5/7: 7 %
  // apart, so a disk given a sphere's inertia (or the reverse) fails by far.
  // Both roll without slipping: before the contact point was put on the
  // round part's surface, the ball's rim slipped 0.2 % and it rolled 0.12 %
  // slow (the surface layer's overlap shortened its rolling radius).
  // At 1e-5 the error is the contact's softness (the friction row's
  // compliance lets the rim creep at about f / c = 1e-5 m/s whatever the step),
  // not the integration: below it a step order means nothing.
  for (const bool cylinder : {true, false}) {
    const std::string name = cylinder ? "rolling disk" : "rolling ball";
    expect_converges(
        name.c_str(), kSteps,
        [&](double dt) {
          const Result r = run_rolling(dt, Method{}, cylinder);
          std::printf("%s at 1/%.0f s: a / (g sin theta) = %.7f (exact %.7f), rim slip %.3g\n",
                      name.c_str(), 1 / dt, r.measured, r.exact, r.stretch);
          EXPECT_LT(r.stretch, 1e-3) << name << " slips at 1/" << 1 / dt << " s";
          EXPECT_TRUE(r.finite) << name;
          return r.error;
        },
        1e-4, 1e-5);
  }
}

}  // namespace
}  // namespace alloy::scenes::analytic
