// Tests for resolvers/magnetism/solenoid_field.hpp: a coil's near field as a
// finite current sheet. Each physics test also shows that the pole pair alone
// fails it (the reason the sheet exists: docs/magnetism.md "A coil's near field").
#include "resolvers/magnetism/solenoid_field.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "resolvers/magnetism/pole_model.hpp"

namespace alloy::magnetism {
namespace {

constexpr double kEps = 0.005;
constexpr double kPi = std::numbers::pi;

// docs/magnetism.md's test coil (adv13 F10): k 0.06 m, poles 4 cm apart, 500 turns.
Solenoid test_coil(Vec3 centre = {}, Vec3 axis = {0, 0, 1}, double k = 0.06, double d = 0.04,
                   double turns = 500) {
  Solenoid s;
  s.centre = centre, s.axis = axis, s.length = d;
  s.radius = solenoid_radius(k, d);
  s.turns_per_metre = turns / d;
  return s;
}

// The flux a magnet (q at north, -q at south) links per ampere in the coil.
// sheet = false: the pole pair alone.
double magnet_flux(const Solenoid& c, Vec3 south, Vec3 north, double q, bool sheet) {
  double phi = q * (pair_linkage(c, kEps, north).flux - pair_linkage(c, kEps, south).flux);
  if (sheet)
    phi += q * (near_correction(c, kEps, north).flux - near_correction(c, kEps, south).flux +
                string_linkage(c, south, north).flux);
  return phi;
}

TEST(SolenoidField, DiskPotentialMatchesItsClosedFormOnTheAxis) {
  const double a = 0.03;
  for (double z : {1e-5, 1e-3, 0.01, 0.03, 0.2, -0.05}) {
    const double exact = 2 * kPi * (std::sqrt(a * a + z * z) - std::abs(z));
    double dr, dz;
    EXPECT_NEAR(disk_potential(a, 0, z, &dr, &dz), exact, 1e-8 * exact) << z;
    // dD/dz = -2 pi (1 - |z|/sqrt(z^2 + a^2)) sign z: the solid angle
    const double slope = -2 * kPi * (1 - std::abs(z) / std::sqrt(a * a + z * z)) * (z < 0 ? -1 : 1);
    EXPECT_NEAR(dz, slope, 2e-5 * std::abs(slope) + 1e-9) << z;
    EXPECT_NEAR(dr, 0.0, 1e-12);
  }
}

TEST(SolenoidField, DiskPotentialGradientIsTheDerivativeOfItsValue) {
  const double a = 0.03, h = 1e-7;
  for (double rho : {0.001, 0.015, 0.029, 0.031, 0.06})
    for (double z : {0.002, 0.01, -0.04}) {
      double dr, dz;
      disk_potential(a, rho, z, &dr, &dz);
      const double fr = (disk_potential(a, rho + h, z) - disk_potential(a, rho - h, z)) / (2 * h);
      const double fz = (disk_potential(a, rho, z + h) - disk_potential(a, rho, z - h)) / (2 * h);
      EXPECT_NEAR(dr, fr, 1e-6 * (std::abs(fr) + 1)) << rho << " " << z;
      EXPECT_NEAR(dz, fz, 1e-6 * (std::abs(fz) + 1)) << rho << " " << z;
    }
}

// A pole q on the axis of a sheet at z_p (|z_p| < l/2): the turns above it
// link mu0 q Omega/(4 pi) each upward, those below the same downward, and
// int_0^L Omega du = 2 pi (L + a - sqrt(L^2 + a^2)), so
//   Phi / I = mu0 N q / (2 l) [(L1 - sqrt(L1^2 + a^2)) - (L2 - sqrt(L2^2 + a^2))],
// L1 = l/2 - z_p, L2 = l/2 + z_p; ~ -mu0 n q z_p... only within a of the
// middle of a long coil it is ~0 (each turn's share falls off beyond a).
TEST(SolenoidField, PoleOnTheAxisOfALongSolenoidLinksTheDerivedFlux) {
  const double a = 0.01, l = 0.4, turns = 2000, q = 1;
  Solenoid s;
  s.axis = {0, 0, 1}, s.length = l, s.radius = a, s.turns_per_metre = turns / l;
  for (double zp : {0.0, 0.05, 0.15, 0.19, -0.12}) {
    const double l1 = l / 2 - zp, l2 = l / 2 + zp;
    const double want = kMu0 * turns * q / (2 * l) *
                        ((l1 - std::sqrt(l1 * l1 + a * a)) - (l2 - std::sqrt(l2 * l2 + a * a)));
    const PoleLinkage got = sheet_linkage(s, {0, 0, zp});
    EXPECT_NEAR(got.flux, want, 0.01 * std::abs(want) + 1e-15) << zp;
  }
  // A magnet (moment m = q d) lying in the middle links mu0 n m: the B
  // inside it passes through every turn its length spans (the string).
  const double d = 0.02;
  const double phi = magnet_flux(s, {0, 0, -d / 2}, {0, 0, d / 2}, q, true);
  EXPECT_NEAR(phi, kMu0 * turns / l * q * d, 0.01 * kMu0 * turns / l * q * d);
  EXPECT_LT(magnet_flux(s, {0, 0, -d / 2}, {0, 0, d / 2}, q, false), 0.0);  // the pair: backwards
}

// A magnet moved along the axis through the coil: the flux it links rises to
// one maximum at the middle and falls again, so the EMF -dPhi/dt has two
// lobes of opposite sign. The pole pair's flux changes sign inside the coil.
TEST(SolenoidField, MagnetThroughACoilInducesTwoLobes) {
  const Solenoid c = test_coil();
  const double q = 100, dm = 0.017;
  auto sign_changes = [&](bool sheet) {
    int changes = 0;
    double last_slope = 0,
           last = magnet_flux(c, {0, 0, -0.15 - dm / 2}, {0, 0, -0.15 + dm / 2}, q, sheet);
    for (int i = 1; i <= 3000; ++i) {
      const double z = -0.15 + 0.3 * i / 3000;
      const double phi = magnet_flux(c, {0, 0, z - dm / 2}, {0, 0, z + dm / 2}, q, sheet);
      const double slope = phi - last;
      if (std::abs(slope) > 1e-12 && last_slope != 0 && (slope > 0) != (last_slope > 0)) ++changes;
      if (std::abs(slope) > 1e-12) last_slope = slope;
      last = phi;
      if (sheet) {
        EXPECT_GT(phi, 0.0) << z;  // one sign all the way
      }
    }
    return changes;
  };
  EXPECT_EQ(sign_changes(true), 1);
  EXPECT_GE(sign_changes(false), 3);  // adv13 F10: six lobes
}

// The flux's gradient is the exact derivative of the flux, window included,
// for a tilted magnet crossing the window's fade, the bore and the end caps.
TEST(SolenoidField, FluxGradientIsExactEverywhereInTheZone) {
  const Solenoid c = test_coil({0.01, 0.02, 0.03}, Vec3{1, 2, 2} / 3.0);
  const double a = c.radius;
  const double h = 1e-8;
  int in_fade = 0;
  for (int i = 0; i < 200; ++i) {
    const double t = i / 199.0;
    const Vec3 p = c.centre + (-0.08 + 0.16 * t) * c.axis +
                   (2.6 * a * std::sin(7 * t)) * Vec3{0, 1, -1} / std::sqrt(2.0);
    const Window w = near_window(c, p);
    if (w.value > 0 && w.value < 1) ++in_fade;
    const PoleLinkage g = near_correction(c, kEps, p);
    for (int k = 0; k < 3; ++k) {
      Vec3 e{};
      (k == 0 ? e.x : k == 1 ? e.y : e.z) = h;
      const double fd =
          (near_correction(c, kEps, p + e).flux - near_correction(c, kEps, p - e).flux) / (2 * h);
      const double an = k == 0 ? g.gradient.x : k == 1 ? g.gradient.y : g.gradient.z;
      EXPECT_NEAR(an, fd, 1e-5 * std::abs(fd) + 1e-12) << i << " " << k;
    }
  }
  EXPECT_GT(in_fade, 10);
}

TEST(SolenoidField, StringGradientIsExactThroughCapsAndWall) {
  const Solenoid c = test_coil({0, 0, 0}, {0, 0, 1});
  const double h = 1e-7;
  struct Case {
    Vec3 s, n;
  };
  // north inside, south below; crossing both caps; tilted through the wall.
  const Case cases[] = {{{0.001, 0, -0.04}, {0.002, 0.001, 0.005}},
                        {{0, 0.003, -0.05}, {0.001, 0, 0.05}},
                        {{-0.04, 0, 0.0}, {0.01, 0.002, 0.012}},
                        {{0.02, 0.01, 0.01}, {-0.005, 0.0, -0.03}}};
  for (const Case& k : cases) {
    const StringLinkage g = string_linkage(c, k.s, k.n);
    EXPECT_NE(g.flux, 0.0);
    for (int axis = 0; axis < 3; ++axis) {
      Vec3 e{};
      (axis == 0 ? e.x : axis == 1 ? e.y : e.z) = h;
      const double fn =
          (string_linkage(c, k.s, k.n + e).flux - string_linkage(c, k.s, k.n - e).flux) / (2 * h);
      const double fs =
          (string_linkage(c, k.s + e, k.n).flux - string_linkage(c, k.s - e, k.n).flux) / (2 * h);
      const double an = axis == 0 ? g.grad_north.x : axis == 1 ? g.grad_north.y : g.grad_north.z;
      const double as = axis == 0 ? g.grad_south.x : axis == 1 ? g.grad_south.y : g.grad_south.z;
      EXPECT_NEAR(an, fn, 1e-5 * std::abs(fn) + 1e-9) << axis;
      EXPECT_NEAR(as, fs, 1e-5 * std::abs(fs) + 1e-9) << axis;
    }
  }
}

// Energy: moving a magnet through the coil at a constant current I, the work
// the coil's force does along the path (the integral of I grad Phi . dx)
// equals I times the change of the flux it links.
TEST(SolenoidField, WorkAtConstantCurrentEqualsCurrentTimesFluxChange) {
  const Solenoid c = test_coil();
  const double q = 100, dm = 0.017, current = 2.0;
  auto flux = [&](Vec3 centre, Vec3 dir) {
    return magnet_flux(c, centre - 0.5 * dm * dir, centre + 0.5 * dm * dir, q, true);
  };
  auto force = [&](Vec3 centre, Vec3 dir) {  // I grad Phi, summed over the magnet's poles
    const Vec3 n = centre + 0.5 * dm * dir, s = centre - 0.5 * dm * dir;
    const StringLinkage st = string_linkage(c, s, n);
    const Vec3 g = q * (pair_linkage(c, kEps, n).gradient + near_correction(c, kEps, n).gradient -
                        pair_linkage(c, kEps, s).gradient - near_correction(c, kEps, s).gradient) +
                   q * (st.grad_north + st.grad_south);
    return current * g;
  };
  // A curved path from far below, in through the bottom end slightly off the
  // axis, out of the top and away across the window's fade. (Not through the
  // winding: a pole grazing the sheet makes the string's length change as a
  // square root, and parts collide there anyway.)
  auto path = [](double t) {
    t *= 1.4;
    const double side = std::max(0.0, t - 0.9);
    return Vec3{0.004 * std::sin(3 * t), 0.006 + 0.4 * side * side, -0.09 + 0.15 * t};
  };
  const Vec3 dir = Vec3{0.1, 0, 1} / std::sqrt(1.01);
  const int steps = 4000;
  double work = 0;
  for (int i = 0; i < steps; ++i) {  // midpoint rule
    const double t0 = double(i) / steps, t1 = double(i + 1) / steps;
    work += dot(force(path(0.5 * (t0 + t1)), dir), path(t1) - path(t0));
  }
  const double delta = current * (flux(path(1), dir) - flux(path(0), dir));
  EXPECT_GT(std::abs(flux(path(0.45), dir)), 1e-4);  // it did pass through
  EXPECT_NEAR(work, delta, 1e-6 * std::abs(current * flux(path(0.45), dir)));
}

// Two coaxial coils wound the same way (adv13 F7's transformer, 500 and 300
// turns, k 0.2 m, 4 cm long): M > 0 at every offset, largest when they
// coincide, and below sqrt(L1 L2) with L from the same sheet, no clamp.
TEST(SolenoidField, CoaxialCoilsCoupleWithOneSignAndBelowTheirInductances) {
  const Solenoid p = test_coil({}, {1, 0, 0}, 0.2, 0.04, 500);
  const double l1 = sheet_self_inductance(p);
  double last = 1e300;
  int pair_negative = 0;
  for (int i = 0; i <= 24; ++i) {
    const double x = 0.005 * i;
    const Solenoid s = test_coil({x, 0, 0}, {1, 0, 0}, 0.2, 0.04, 300);
    const double l2 = sheet_self_inductance(s);
    const double m = sheet_mutual_inductance(p, s, kEps);
    EXPECT_GT(m, 0.0) << x;
    EXPECT_LT(m, std::sqrt(l1 * l2)) << x;
    EXPECT_LT(m, last * (1 + 1e-12)) << x;  // falls as they part
    last = m;
    // the pole pair's M: k1 N1 k2 N2 mu0/4pi (1/s(S1-N2) - 1/s(S1-S2) - 1/s(N1-N2) + 1/s(N1-S2))
    const double q1 = 0.2 * 500, q2 = 0.2 * 300;
    auto inv = [](double r) { return 1 / std::sqrt(r * r + kEps * kEps); };
    const double pair = q1 * q2 * kMu0Over4Pi *
                        (inv(-0.02 - (x + 0.02)) - inv(-0.02 - (x - 0.02)) -
                         inv(0.02 - (x + 0.02)) + inv(0.02 - (x - 0.02)));
    if (pair < 0) ++pair_negative;
  }
  EXPECT_GT(pair_negative, 3);  // the pole pair flips the sign when they overlap (F7)
}

// The sheet's self-inductance tends to the long-coil expansion
// mu0 N^2 pi a^2 / l (1 - 8 a / (3 pi l)) and, for a short coil, to Nagaoka's
// tabulated coefficient (l = 2a: K = 0.6884).
TEST(SolenoidField, SelfInductanceMatchesNagaoka) {
  Solenoid s;
  s.axis = {0, 0, 1}, s.radius = 0.01, s.length = 0.8, s.turns_per_metre = 1000;
  const double a = s.radius, l = s.length, n = s.turns_per_metre;
  const double ideal = kMu0 * n * n * kPi * a * a * l;
  EXPECT_NEAR(sheet_self_inductance(s) / ideal, 1 - 8 * a / (3 * kPi * l), 1e-4);
  s.length = 2 * a;
  EXPECT_NEAR(sheet_self_inductance(s) / (kMu0 * n * n * kPi * a * a * s.length), 0.6884, 0.002);
}

// Outside the zone the correction is exactly zero: the far field, the tree
// sums and every scene whose poles stay away keep their bits.
TEST(SolenoidField, CorrectionIsExactlyZeroOutsideTheZone) {
  const Solenoid c = test_coil();
  const double a = c.radius;
  for (Vec3 p : {Vec3{0, 0, 0.02 + 5.01 * a}, Vec3{5.01 * a, 0, 0}, Vec3{0.3, 0.2, -0.1}}) {
    const PoleLinkage g = near_correction(c, kEps, p);
    EXPECT_EQ(g.flux, 0.0);
    EXPECT_EQ(g.gradient, Vec3{});
  }
  EXPECT_EQ(string_linkage(c, {0.1, 0, -0.1}, {0.1, 0, 0.1}).flux, 0.0);  // beside the bore
  EXPECT_EQ(near_window(c, {0, 0.9 * a, 0.01}).value, 1.0);
}

}  // namespace
}  // namespace alloy::magnetism
