// Tests for resolvers/magnetism/pole_model.hpp against closed forms: Coulomb's
// law for poles, the softened kernel's bound, Newton's third law of the
// summation, the torque on a dipole in a uniform field, the demagnetising
// factors of spheroids, and the induction solve (linear, saturated, coupled).
#include "resolvers/magnetism/pole_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace alloy::magnetism {
namespace {

constexpr double kPi = std::numbers::pi;

/// Unsoftened Coulomb law for poles, written independently of the kernel.
Vec3 coulomb(double q1, Vec3 x1, double q2, Vec3 x2) {
  const Vec3 r = x2 - x1;
  const double d = length(r);
  return r * (1e-7 * q1 * q2 / (d * d * d));
}

TEST(MagnetismPoleModel, PairForceIsCoulombsLawFarFromTheSofteningLength) {
  const double eps = 0.005;
  for (double r : {0.05, 0.1, 1.0}) {
    const Vec3 f = pole_pair_force(2.0, {0, 0, 0}, 3.0, {r, 0, 0}, eps);
    const Vec3 ref = coulomb(2.0, {0, 0, 0}, 3.0, {r, 0, 0});
    // Plummer softening: relative deficit 1 - (1 + eps^2/r^2)^(-3/2) ~ 1.5 (eps/r)^2.
    const double expected = std::pow(1 + eps * eps / (r * r), -1.5);
    EXPECT_NEAR(f.x / ref.x, expected, 1e-9) << "r = " << r;
    EXPECT_GT(f.x, 0) << "like poles repel";
  }
  // Unlike poles attract: the force on pole 2 points back at pole 1.
  EXPECT_LT(pole_pair_force(2.0, {0, 0, 0}, -3.0, {0.1, 0, 0}, eps).x, 0);
  // mu0 / 4 pi is 1e-7 N/A^2 to 1e-9 (CODATA 2018).
  EXPECT_NEAR(kMu0Over4Pi, 1e-7, 1e-16);
}

TEST(MagnetismPoleModel, SofteningKeepsTouchingPolesFinite) {
  const double eps = 0.005, q = 50.0;
  // The softened force peaks at r = eps / sqrt(2) with k q^2 2 / (3 sqrt(3) eps^2).
  const double bound = kMu0Over4Pi * q * q * 2.0 / (3.0 * std::sqrt(3.0) * eps * eps);
  double peak = 0;
  for (int i = 0; i <= 1000; ++i) {
    const double r = 1e-5 * i;
    const Vec3 f = pole_pair_force(q, {0, 0, 0}, q, {r, 0, 0}, eps);
    ASSERT_TRUE(is_finite(f));
    peak = std::max(peak, length(f));
  }
  EXPECT_LE(peak, bound * (1 + 1e-12));
  EXPECT_GT(peak, bound * 0.999);
  // Coincident poles: finite (zero), with or without softening.
  EXPECT_EQ(pole_pair_force(q, {1, 2, 3}, q, {1, 2, 3}, eps), Vec3{});
  EXPECT_EQ(pole_pair_force(q, {1, 2, 3}, q, {1, 2, 3}, 0.0), Vec3{});
}

TEST(MagnetismPoleModel, SummedForcesObeyNewtonsThirdLaw) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Pole> poles;
  for (std::uint32_t b = 0; b < 20; ++b) {
    const Vec3 c{u(rng), u(rng), 0.1 * u(rng)};
    const double q = 10 * u(rng);
    poles.push_back({c + Vec3{0.05, 0, 0}, q, b});
    poles.push_back({c - Vec3{0.05, 0, 0}, -q, b});
  }
  std::vector<Vec3> f(poles.size());
  accumulate_pole_forces(poles, 0.005, f);
  Vec3 total, scale_sum;
  for (const Vec3& v : f)
    total += v, scale_sum += Vec3{std::abs(v.x), std::abs(v.y), std::abs(v.z)};
  EXPECT_LE(length(total), 1e-14 * length(scale_sum));
  // A part never pushes itself: one bar alone feels nothing.
  std::vector<Vec3> alone(2);
  accumulate_pole_forces(std::span(poles).first(2), 0.005, alone);
  EXPECT_EQ(alone[0], Vec3{});
  EXPECT_EQ(alone[1], Vec3{});
}

TEST(MagnetismPoleModel, SmallBarInAUniformFieldFeelsTheDipoleTorqueAndNoForce) {
  // A long "field magnet" far away makes a nearly uniform field at the origin;
  // a short bar there feels tau = m x B with m = q d along its axis.
  const double Q = 1e4, qs = 1.0, d = 0.01;
  std::vector<Pole> poles = {{{-50, 0, 0}, Q, 0}, {{-1e6, 0, 0}, -Q, 0}};
  Vec3 h[1];
  const std::uint32_t none = kNoBody;
  const Vec3 origin{};
  pole_fields(poles, 0.0, std::span(&origin, 1), std::span(&none, 1), h);
  const Vec3 b = h[0] * kMu0;  // along +x: away from the distant north pole
  ASSERT_GT(b.x, 0);
  const BarPoles bar = bar_poles({0, 0, 0}, {0, 1, 0}, d);  // perpendicular to B
  poles.push_back({bar.north, qs, 1});
  poles.push_back({bar.south, -qs, 1});
  std::vector<Vec3> f(poles.size());
  accumulate_pole_forces(poles, 0.0, f);
  const Vec3 force = f[2] + f[3];
  const Vec3 torque = cross(bar.north, f[2]) + cross(bar.south, f[3]);
  const Vec3 expected = cross(Vec3{0, qs * d, 0}, b);  // -z: turns north toward +x
  EXPECT_NEAR(torque.z, expected.z, 1e-6 * std::abs(expected.z));
  EXPECT_LT(torque.z, 0);
  EXPECT_LT(length(force), 1e-3 * std::abs(expected.z) / d);  // a gradient force only
}

TEST(MagnetismPoleModel, DemagnetizingFactorsOfSpheroids) {
  EXPECT_NEAR(demagnetizing_factor(1.0), 1.0 / 3.0, 1e-12);
  // Both branches meet the series at the sphere.
  EXPECT_NEAR(demagnetizing_factor(1.0 + 1.1e-3), demagnetizing_factor(1.0 + 0.9e-3), 1e-4);
  EXPECT_NEAR(demagnetizing_factor(1.0 - 1.1e-3), demagnetizing_factor(1.0 - 0.9e-3), 1e-4);
  // Tabulated (Osborn 1945): prolate p = 2: 0.1736; p = 5: 0.0558; oblate p = 0.5: 0.5272.
  EXPECT_NEAR(demagnetizing_factor(2.0), 0.1736, 1e-4);
  EXPECT_NEAR(demagnetizing_factor(5.0), 0.0558, 1e-4);
  EXPECT_NEAR(demagnetizing_factor(0.5), 0.5272, 1e-4);
  // A needle hardly demagnetises, a flat disc fully.
  EXPECT_LT(demagnetizing_factor(100.0), 1e-3);
  EXPECT_GT(demagnetizing_factor(0.01), 0.98);
  // Apparent susceptibility saturates at 1 / N however large chi is.
  EXPECT_NEAR(apparent_susceptibility(1e9, 0.1), 10.0, 1e-6);
}

TEST(MagnetismPoleModel, InducedPoleIsLinearInTheFieldThenSaturates) {
  // One source pole far to the left: nearly uniform H along +x at the bar.
  const double Q = 1000, R = 10;
  const std::vector<Pole> source = {{{-R, 0, 0}, Q, 0}};
  const double h = Q / (4 * kPi * R * R);
  InducedBar bar{
      .centre = {}, .axis = {1, 0, 0}, .separation = 0.1, .gain = 2e-3, .saturation = 0, .body = 1};
  auto solve = [&](double qsat) {
    bar.saturation = qsat;
    return solve_induction(source, std::span(&bar, 1), 0.0).strength[0];
  };
  EXPECT_NEAR(solve(0.0), 2e-3 * h, 1e-4 * 2e-3 * h);  // no saturation: linear
  const double qsat = 2e-3 * h;                        // saturation at the linear value
  EXPECT_NEAR(solve(qsat), qsat * std::tanh(1.0), 1e-4 * qsat);
  EXPECT_LT(solve(qsat), qsat);
  // A bar across the field is not magnetised along its axis.
  bar.axis = {0, 1, 0};
  EXPECT_NEAR(solve(0.0), 0.0, 1e-9 * 2e-3 * h);
}

TEST(MagnetismPoleModel, CoupledBarsInAChainReinforceEachOtherConsistently) {
  const std::vector<Pole> source = {{{-0.2, 0, 0}, 20.0, 0}, {{-0.3, 0, 0}, -20.0, 0}};
  std::vector<InducedBar> bars = {
      {.centre = {-0.1, 0, 0},
       .axis = {1, 0, 0},
       .separation = 0.085,
       .gain = 7e-3,
       .saturation = 800,
       .body = 1},
      {.centre = {0.005, 0, 0},
       .axis = {1, 0, 0},
       .separation = 0.085,
       .gain = 7e-3,
       .saturation = 800,
       .body = 2},
  };
  const InductionResult r = solve_induction(source, bars, 0.005);
  ASSERT_TRUE(r.converged);
  EXPECT_GE(r.iterations, 1);
  // Uncoupled estimates, bar by bar.
  std::vector<double> alone;
  for (const InducedBar& b : bars)
    alone.push_back(solve_induction(source, std::span(&b, 1), 0.005).strength[0]);
  EXPECT_GT(r.strength[0], alone[0]);  // a chain of iron magnetises more than its links
  EXPECT_GT(r.strength[1], alone[1]);
  // The answer satisfies the equations: recompute each bar's axial field.
  for (std::size_t b = 0; b < bars.size(); ++b) {
    std::vector<Pole> others = source;
    for (std::size_t c = 0; c < bars.size(); ++c) {
      if (c == b) continue;
      const BarPoles p = bar_poles(bars[c].centre, bars[c].axis, bars[c].separation);
      others.push_back({p.north, r.strength[c], bars[c].body});
      others.push_back({p.south, -r.strength[c], bars[c].body});
    }
    double axial = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec3 x = bars[b].centre + bars[b].axis * ((k - 1) * 0.5 * bars[b].separation);
      Vec3 h;
      const std::uint32_t self = bars[b].body;
      pole_fields(others, 0.005, std::span(&x, 1), std::span(&self, 1), std::span(&h, 1));
      axial += kAxialSampleWeights[k] * h.x;
    }
    EXPECT_NEAR(r.strength[b], saturate(bars[b].gain * axial, 800), 1e-9 * std::abs(r.strength[b]));
  }
}

}  // namespace
}  // namespace alloy::magnetism
