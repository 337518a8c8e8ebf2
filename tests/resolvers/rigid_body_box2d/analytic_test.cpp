// The rigid body's closed-form cases (tests/resolvers/rigid_body/closed_form_test.cpp,
// the scenes of tests/scenes/analytic_scenes) that apply to the plane, run on
// rigid_body.box2d at 1/240, 1/480 and 1/960 s with the bounds ODE's tests hold.
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

Method box2d() {
  Method m;
  m.engine = "rigid_body.box2d";
  return m;
}

std::vector<double> errors(const char* name, const std::vector<double>& dts,
                           const std::function<double(double)>& what) {
  std::vector<double> e;
  for (double dt : dts) {
    e.push_back(what(dt));
    std::printf("box2d %s at 1/%.0f s: %.3g\n", name, 1 / dt, e.back());
  }
  return e;
}

/// Checks the error at 1/240 s against ODE's bound; where Box2D misses it,
/// against the figure measured when this was written (`missed`, kept within
/// 10 % so that a change either way is seen, and printed as a miss), and that
/// the error does not grow as the step falls (a 2 % allowance for float
/// rounding), unless every error is at rounding level (`floor`).
void expect_case(const char* name, const std::vector<double>& e, double bound, double missed = 0,
                 double floor = 1e-6) {
  if (missed > 0) {
    std::printf("box2d %s: MISSES ODE's bound %.3g at 1/240 s: %.3g\n", name, bound, e.front());
    EXPECT_NEAR(e.front(), missed, 0.1 * missed) << name;
  } else {
    EXPECT_LE(e.front(), bound) << name;
  }
  bool tiny = true;
  for (double x : e) tiny = tiny && x <= floor;
  if (tiny) return;
  for (std::size_t i = 1; i < e.size(); ++i) EXPECT_LE(e[i], e[i - 1] * 1.02 + floor) << name;
}

TEST(Box2DClosedForm, FreeFallAndPendulum) {
  expect_case(
      "free fall",
      errors("free fall (m)", kSteps, [](double dt) { return run_free_fall(dt, box2d()).error; }),
      9.81 * 1.0 / 240 / 2 * 1.05);
  expect_case("pendulum 0.5 rad",
              errors("bar pendulum at 0.5 rad, angle error (rad)", kSteps,
                     [](double dt) { return run_pendulum(dt, box2d(), 0.5).error; }),
              0.01);
}

TEST(Box2DClosedForm, ElasticPairsSwapVelocitiesExactly) {
  const std::vector<double> all = {1.0 / 60, 1.0 / 240, 1.0 / 960};
  for (double ratio : {1.0, 3.0})
    expect_case("elastic pair",
                errors("elastic pair, |v - v_exact| (m/s)", all,
                       [ratio](double dt) { return run_elastic_pair(dt, box2d(), ratio).error; }),
                1e-6);
}

TEST(Box2DClosedForm, NewtonsCradleIsMissedBySequentialImpulses) {
  // Box2D solves the four touching contacts one after another, each with
  // restitution on its own approach speed: the momentum spreads over the
  // balls instead of passing to the last (0.6 m/s off at every step). ODE's
  // test holds 1e-6.
  expect_case("cradle",
              errors("cradle, |v - (0,0,0,0,1)| (m/s)", kSteps,
                     [](double dt) { return run_cradle(dt, box2d()).error; }),
              1e-6, 0.6);
}

TEST(Box2DClosedForm, BounceReboundsToRestitutionSquared) {
  // ODE's bound 0.03 at 1/240 s. The sign of the error changes between the
  // steps (see box2d_test.cpp), so only the bound is checked at each.
  for (double e : {0.5, 0.9}) {
    const auto err = errors("bounce, |h1/h0 / e^2 - 1|", kSteps,
                            [e](double dt) { return run_bounce(dt, box2d(), e).error; });
    for (double x : err) EXPECT_LE(x, 0.03) << "e " << e;
  }
}

// Hinges over a large swing: Box2D's revolute joint holds its length to 2e-7
// (ODE's bound 1e-3) but loses the swing's energy (5.5 % a period at 90
// degrees, 9.9 % at 170), as ODE's hinge did before its projection: the
// period at 170 degrees, near the top where the period is most sensitive to
// energy, comes out 40 % short. ODE's bounds: 0.5 % period, 0.1 % drift.
TEST(Box2DClosedForm, LeverAndBarOnAHingeHoldTheirLengthButLoseEnergy) {
  const double p90 = 90 * kPi / 180, p170 = 170 * kPi / 180;
  expect_case("lever 90 stretch",
              errors("lever 90 deg, stretch", kSteps,
                     [&](double dt) { return run_swing(dt, box2d(), true, p90).stretch; }),
              1e-3, 0, 1e-6);
  expect_case("lever 90 period",
              errors("lever 90 deg, period error", kSteps,
                     [&](double dt) { return run_swing(dt, box2d(), true, p90).error; }),
              5e-3, 0.0163);
  expect_case("lever 90 drift",
              errors("lever 90 deg, energy drift per period", kSteps,
                     [&](double dt) { return run_swing(dt, box2d(), true, p90).energy_drift; }),
              1e-3, 0.0551);
  expect_case("lever 170 stretch",
              errors("lever 170 deg, stretch", kSteps,
                     [&](double dt) { return run_swing(dt, box2d(), true, p170).stretch; }),
              1e-3, 0, 1e-6);
  expect_case("lever 170 period",
              errors("lever 170 deg, period error", kSteps,
                     [&](double dt) { return run_swing(dt, box2d(), true, p170).error; }),
              5e-3, 0.403);
  expect_case("bar 170 period",
              errors("bar 170 deg, period error", kSteps,
                     [&](double dt) { return run_swing(dt, box2d(), false, p170).error; }),
              5e-3, 0.395);
}

TEST(Box2DClosedForm, ChainAtAThousandToOneStretches) {
  // ODE's bound: the chain's gaps at 1e-3 of its length. Box2D's iterations
  // cannot hold a 10 kg ball on 10 g links at one substep: 15 % at 1/240 s,
  // falling at second order with the step (4.4 %, 1.1 %). bench/stress-style
  // substeps hold it (Box2DStress.ChainAtThousandToOneHoldsWithSubsteps).
  expect_case("heavy chain gap",
              errors("heavy chain, gap / length", kSteps,
                     [](double dt) { return run_heavy_chain(dt, box2d()).error; }),
              1e-3, 0.154);
}

TEST(Box2DClosedForm, DiskAndBallRollDownASlope) {
  // ODE's bound 1e-4 of the acceleration at 1/240 s; Box2D rolls 0.1 %
  // fast-or-slow there (the rim slips 0.16 % while its friction warms up)
  // and within 7e-5 at 1/960 s. Not monotone for the disk (3e-6 at 1/480).
  for (const bool cylinder : {true, false}) {
    const auto e =
        errors(cylinder ? "rolling disk, |a / a_exact - 1|" : "rolling ball, |a / a_exact - 1|",
               kSteps, [&](double dt) { return run_rolling(dt, box2d(), cylinder).error; });
    std::printf("box2d rolling %s: MISSES ODE's bound 1e-4 at 1/240 s: %.3g\n",
                cylinder ? "disk" : "ball", e.front());
    EXPECT_NEAR(e.front(), cylinder ? 1.07e-3 : 9.16e-4, 1e-4);
    EXPECT_LT(e.back(), 1e-4);
  }
}

}  // namespace
}  // namespace alloy::scenes::analytic
