// Accuracy against analytic solutions at the default step (1/240 s): the
// acceptance criteria of the rigid body. Each test prints its measured error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

constexpr double g = 9.81;

TEST(RigidBodyAccuracy, FreeFallErrorIsSemiImplicitEulers) {
  Sim s;
  const FreeFall ff = build_free_fall(*s, 10);
  const double T = 2.0;
  s.run_for(T);
  const double dt = s->dt();
  const double exact = ff.start.y - 0.5 * g * T * T;
  // Semi-implicit Euler: x_n = x0 - g dt^2 n (n + 1) / 2, i.e. below the exact
  // parabola by g T dt / 2.
  const double expected_error = 0.5 * g * T * dt;
  const double error = exact - s.position(ff.ball).y;
  std::printf("free fall: error %.6f m, 1/2 g T dt = %.6f m, ratio %.6f\n", error, expected_error,
              error / expected_error);
  EXPECT_NEAR(error, expected_error, 0.01 * expected_error);
  EXPECT_EQ(s.position(ff.ball).x, 0.0);
}

TEST(RigidBodyAccuracy, HingedBarPeriodMatchesCompoundPendulum) {
  Sim s;
  const BarPendulum p = build_bar_pendulum(*s, 1.0, 0.05);
  const double dt = s->dt();
  // Upward zero crossings of the swing angle, interpolated within the step.
  auto swing = [&] { return angle_z(s.orientation(p.bar)) + std::numbers::pi / 2; };
  std::vector<double> crossings;
  double prev = swing();
  for (int i = 1; i <= int(12.0 / dt); ++i) {
    s->step();
    const double a = swing();
    if (prev < 0 && a >= 0) crossings.push_back((i - 1 + prev / (prev - a)) * dt);
    prev = a;
  }
  ASSERT_GE(crossings.size(), 5u);
  const double period = (crossings.back() - crossings.front()) / double(crossings.size() - 1);
  const double exact = p.analytic_period(g);
  const double rel = period / exact - 1;
  std::printf("pendulum: period %.6f s, analytic %.6f s, error %.4f%%\n", period, exact, 100 * rel);
  EXPECT_LT(std::abs(rel), 0.005);
  // The pivot holds: the bar's top end stays at the origin.
  const Vec3 top = s.position(p.bar) + rotate(s.orientation(p.bar), Vec3{-p.length / 2, 0, 0});
  EXPECT_LT(length(top), 1e-3);
}

TEST(RigidBodyAccuracy, BounceHeightRatioIsRestitutionSquared) {
  for (double e : {0.5, 0.7, 0.9}) {
    Sim s;
    const Bounce b = build_bounce(*s, 1.0, e);
    // First rebound: the highest point after the velocity turns upward.
    bool rebounded = false;
    double top = -1;
    for (int i = 0; i < int(3.0 / s->dt()); ++i) {
      s->step();
      const double vy = s.velocity(b.ball).y, y = s.position(b.ball).y - b.radius;
      if (!rebounded && vy > 0) rebounded = true;
      if (rebounded) {
        if (vy < 0) break;
        top = std::max(top, y);
      }
    }
    ASSERT_TRUE(rebounded);
    const double ratio = top / b.drop;
    const double rel = ratio / (e * e) - 1;
    std::printf("bounce e=%.1f: rebound ratio %.4f, e^2 %.4f, error %.2f%%\n", e, ratio, e * e, 100 * rel);
    EXPECT_LT(std::abs(rel), 0.05) << "e = " << e;
  }
}

TEST(RigidBodyAccuracy, DragLimitedSpeedIsExactAtAnyStep) {
  // A ball falling with linear damping c settles at g / c. The step's kick and
  // drift must agree on it: ODE's own damping (e^(-c h) after the drift) ran
  // the position c h / 2 fast and reported the velocity c h / 2 slow.
  const double c = 2;
  for (double dt : {1.0 / 60, 1.0 / 240}) {
    Sim s(WorldDef{.dt = dt});
    const FreeFall ff = build_free_fall(*s, 1000);
    s->set(ff.ball, "linear_damping", c);
    s.run_for(10.0);  // 20 time constants
    const double y0 = s.position(ff.ball).y;
    s.run_for(1.0);
    const double from_position = y0 - s.position(ff.ball).y;
    const double reported = -s.velocity(ff.ball).y;
    std::printf("terminal speed at dt 1/%.0f: from the position %.7f, reported %.7f, g / c %.7f\n",
                1 / dt, from_position, reported, g / c);
    EXPECT_NEAR(from_position, g / c, 1e-6 * g / c) << "dt " << dt;
    EXPECT_NEAR(reported, g / c, 1e-6 * g / c) << "dt " << dt;
  }
  // Damping faster than the step (c h = 3): still falls, never reverses.
  Sim s(WorldDef{.dt = 1.0 / 60});
  const FreeFall ff = build_free_fall(*s, 1000);
  s->set(ff.ball, "linear_damping", 180.0);
  for (int i = 0; i < 120; ++i) {
    s->step();
    const double vy = s.velocity(ff.ball).y;
    ASSERT_LT(vy, 0) << "step " << i;
    ASSERT_GT(vy, -2 * g / 60) << "step " << i;  // about one step's fall
  }
}

TEST(RigidBodyAccuracy, StackOfTenStandsForTenSeconds) {
  Sim s;
  const Stack st = build_stack(*s, 10, 0.2);
  const Vec3 start = s.position(st.boxes.back());
  s.run_for(10.0);
  const Vec3 end = s.position(st.boxes.back());
  const double drift = length(end - start);
  std::printf("stack of 10: top box moved %.5f m (dx %.2e dy %.2e dz %.2e)\n", drift, end.x - start.x,
              end.y - start.y, end.z - start.z);
  EXPECT_LT(drift, 0.01);
}

}  // namespace
}  // namespace alloy::scenes
