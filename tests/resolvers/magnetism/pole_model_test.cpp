// Tests for resolvers/magnetism/pole_model.hpp against closed forms: Coulomb's
// law for poles, the softened kernel's bound, Newton's third law of the
// summation, the torque on a dipole in a uniform field, the demagnetising
// factors of spheroids, and the induction solve (linear, saturated, coupled).
#include "resolvers/magnetism/pole_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

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

TEST(MagnetismPoleModel, CylindersOnAxisFieldAgainstTheClosedForm) {
  // A uniformly magnetised cylinder (Br 1.2 T, radius R = 5 mm, length 20 mm)
  // has the on-axis field B(z) = Br/2 [(z+L)/sqrt((z+L)^2+R^2) - z/sqrt(z^2+R^2)]
  // at z beyond its north face. The pole model carries its moment M pi R^2 L
  // on two poles d apart, softened by eps. Measured ratios model / closed
  // form at z = 0.2, 0.5, 1, 2, 5, 10 R:
  //   d = 0.85 L, eps = 5 mm (the default): 0.23 0.37 0.54 0.74 0.92 0.97
  //   d = 0.85 L, eps = R/2:                1.02 1.00 0.94 0.93 0.97 0.99
  //   d = L (soft iron's), eps = R/2:       0.79 1.29 1.24 1.09 1.02 1.01
  // The default softening understates the field within a radius of the face
  // by up to 4x; a softening of half the face's radius would hold the whole
  // axis to 7 % (a per-part softening: docs/magnetism.md "Soft iron",
  // left for a later session); every choice is the point pole's far away.
  constexpr double kBr = 1.2, R = 0.005, L = 0.02;
  const double m = kBr / kMu0 * std::numbers::pi * R * R * L;  // A m^2
  auto closed = [&](double z) {
    return kBr / 2 *
           ((z + L) / std::sqrt((z + L) * (z + L) + R * R) - z / std::sqrt(z * z + R * R));
  };
  auto model = [&](double z, double d, double eps) {
    const std::vector<Pole> poles = {{{L / 2 - (L - d) / 2, 0, 0}, m / d, 0},
                                     {{-L / 2 + (L - d) / 2, 0, 0}, -m / d, 0}};
    const Vec3 at{L / 2 + z, 0, 0};
    const std::uint32_t none = kNoBody;
    Vec3 h;
    pole_fields(poles, eps, std::span(&at, 1), std::span(&none, 1), std::span(&h, 1));
    return kMu0 * h.x / closed(z);
  };
  const double zs[] = {0.2, 0.5, 1, 2, 5, 10};
  const double expected[3][6] = {{0.23, 0.37, 0.54, 0.74, 0.92, 0.97},
                                 {1.02, 1.00, 0.94, 0.93, 0.97, 0.99},
                                 {0.79, 1.29, 1.24, 1.09, 1.02, 1.01}};
  const double settings[3][2] = {{kMagneticLengthRatio * L, 0.005},
                                 {kMagneticLengthRatio * L, R / 2},
                                 {kInducedLengthRatio * L, R / 2}};
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < 6; ++i)
      EXPECT_NEAR(model(zs[i] * R, settings[c][0], settings[c][1]), expected[c][i], 0.006)
          << "case " << c << " at z = " << zs[i] << " R";
  // Far away, the dipole: within 0.5 % at 40 R whatever the settings.
  for (const auto& s : settings) EXPECT_NEAR(model(40 * R, s[0], s[1]), 1.0, 5e-3);
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

/// An iron part at `centre` with principal axes x, y, z, intrinsic chi and
/// the demagnetising factors of the ellipsoid of semi-axes `semi`.
InducedPart iron_part(Vec3 centre, Vec3 semi, double chi, double saturation, std::uint32_t body) {
  InducedPart p;
  p.centre = centre;
  p.axes[0] = {1, 0, 0}, p.axes[1] = {0, 1, 0}, p.axes[2] = {0, 0, 1};
  const Vec3 n = demagnetizing_factors(semi);
  p.susceptibility[0] = apparent_susceptibility(chi, n.x);
  p.susceptibility[1] = apparent_susceptibility(chi, n.y);
  p.susceptibility[2] = apparent_susceptibility(chi, n.z);
  p.separation[0] = 1.7 * semi.x, p.separation[1] = 1.7 * semi.y, p.separation[2] = 1.7 * semi.z;
  p.volume = 4.0 / 3.0 * kPi * semi.x * semi.y * semi.z;
  p.saturation = saturation;
  p.body = body;
  return p;
}

TEST(MagnetismPoleModel, InducedMomentIsLinearInTheFieldThenSaturates) {
  // One source pole far to the left: nearly uniform H along +x at the part.
  const double Q = 1000, R = 10;
  const std::vector<Pole> source = {{{-R, 0, 0}, Q, 0}};
  const double h = Q / (4 * kPi * R * R);
  InducedPart part = iron_part({}, {0.05, 0.01, 0.01}, 1000, 0, 1);
  const double linear = part.volume * part.susceptibility[0] * h;
  auto solve = [&](double msat) {
    part.saturation = msat;
    return solve_induction(source, std::span(&part, 1), 0.0).moment[0];
  };
  EXPECT_NEAR(solve(0.0).x, linear, 1e-4 * linear);  // no saturation: linear
  EXPECT_NEAR(solve(linear).x, linear * std::tanh(1.0),
              1e-4 * linear);  // saturation at the linear value
  EXPECT_LT(solve(linear).x, linear);
  // Turned across the field, the same bar takes the transverse response.
  std::swap(part.axes[0], part.axes[1]);
  EXPECT_NEAR(solve(0.0).x, part.volume * part.susceptibility[1] * h, 1e-4 * linear);
  EXPECT_LT(part.susceptibility[1], part.susceptibility[0] / 5) << "shape anisotropy";
}

TEST(MagnetismPoleModel, CoupledPartsInAChainReinforceEachOtherConsistently) {
  const std::vector<Pole> source = {{{-0.2, 0, 0}, 20.0, 0}, {{-0.3, 0, 0}, -20.0, 0}};
  const std::vector<InducedPart> parts = {
      iron_part({-0.1, 0, 0}, {0.05, 0.01, 0.01}, 1000, 1.0, 1),
      iron_part({0.005, 0.01, 0}, {0.05, 0.01, 0.01}, 1000, 1.0, 2),
  };
  const InductionResult r = solve_induction(source, parts, 0.005);
  ASSERT_TRUE(r.converged);
  EXPECT_GE(r.iterations, 1);
  std::vector<Vec3> alone;
  for (const InducedPart& p : parts)
    alone.push_back(solve_induction(source, std::span(&p, 1), 0.005).moment[0]);
  EXPECT_GT(r.moment[0].x, alone[0].x);  // a chain of iron magnetises more than its links
  EXPECT_GT(r.moment[1].x, alone[1].x);
  // The answer satisfies the equations: each part's mean field from the
  // source and the other part's three axial pole pairs.
  for (std::size_t b = 0; b < parts.size(); ++b) {
    std::vector<Pole> others = source;
    const std::size_t c = 1 - b;
    for (int j = 0; j < 3; ++j) {
      const double d = parts[c].separation[j];
      const double q = dot(r.moment[c], parts[c].axes[j]) / d;
      const BarPoles p = bar_poles(parts[c].centre, parts[c].axes[j], d);
      others.push_back({p.north, q, parts[c].body});
      others.push_back({p.south, -q, parts[c].body});
    }
    const MeanFieldSamples s = mean_field_samples(parts[b]);
    Vec3 mean{};
    for (int k = 0; k < s.count; ++k) {
      Vec3 hk;
      const std::uint32_t self = parts[b].body;
      pole_fields(others, 0.005, std::span(&s.point[k], 1), std::span(&self, 1), std::span(&hk, 1));
      mean += hk * s.weight[k];
    }
    Vec3 u{};
    for (int i = 0; i < 3; ++i)
      u += parts[b].axes[i] *
           (parts[b].volume * parts[b].susceptibility[i] * dot(parts[b].axes[i], mean));
    const Vec3 expected = saturate_moment(u, 1.0);
    EXPECT_LT(length(r.moment[b] - expected), 1e-9 * length(expected));
  }
}

}  // namespace
}  // namespace alloy::magnetism
