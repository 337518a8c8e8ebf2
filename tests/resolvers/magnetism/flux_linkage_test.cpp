// Tests for resolvers/magnetism/flux_linkage.hpp against the pole model's own
// force law: the force a coil's current puts on a magnet is I grad Phi (so
// the EMF -dPhi/dt and the mechanical work are one quantity), and the rate
// coil_flux reports is the derivative of the flux along the motion.
#include "resolvers/magnetism/flux_linkage.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace alloy::magnetism {
namespace {

constexpr double kEps = 0.005;

Vec3 unit(Vec3 a) {
  return a / length(a);
}

/// A bar's two poles, its body index b.
std::vector<Pole> bar(Vec3 centre, Vec3 axis, double d, double q, std::uint32_t b) {
  const BarPoles p = bar_poles(centre, axis, d);
  return {{p.north, q, b}, {p.south, -q, b}};
}

CoilGeometry coil_at(Vec3 centre, Vec3 axis) {
  CoilGeometry c;
  c.centre = centre;
  c.axis = axis;
  c.separation = 0.04;
  c.linkage = 0.06 * 500;
  c.body = 7;
  return c;
}

TEST(FluxLinkage, ForceOfTheCoilsCurrentIsCurrentTimesTheFluxGradient) {
  // A magnet off the coil's axis and tilted: no symmetry to hide a sign.
  const Vec3 m_centre{0.05, 0.02, 0.01}, m_axis = unit(Vec3{0.3, 1, 0.2});
  const double d = 0.017, q = 100, current = 1.7;
  const CoilGeometry coil = coil_at({0, 0, 0}, unit(Vec3{1, 0.1, 0}));
  // The coil carrying `current`: poles +-k N I (magnet_parts.hpp).
  std::vector<Pole> poles = bar(m_centre, m_axis, d, q, 1);
  const auto coil_poles = bar(coil.centre, coil.axis, coil.separation, coil.linkage * current, 7);
  poles.insert(poles.end(), coil_poles.begin(), coil_poles.end());
  std::vector<Vec3> force(poles.size());
  accumulate_pole_forces(poles, kEps, force);
  const Vec3 on_magnet = force[0] + force[1];

  // grad Phi with respect to the magnet's position, by central differences.
  const double h = 1e-7;
  Vec3 grad;
  for (int k = 0; k < 3; ++k) {
    Vec3 step{};
    (k == 0 ? step.x : k == 1 ? step.y : step.z) = h;
    const auto plus = bar(m_centre + step, m_axis, d, q, 1);
    const auto minus = bar(m_centre - step, m_axis, d, q, 1);
    const double g =
        (coil_flux(plus, {}, kEps, coil).flux - coil_flux(minus, {}, kEps, coil).flux) / (2 * h);
    (k == 0 ? grad.x : k == 1 ? grad.y : grad.z) = g;
  }
  const Vec3 expected = grad * current;
  EXPECT_NEAR(on_magnet.x, expected.x, 1e-6 * length(expected));
  EXPECT_NEAR(on_magnet.y, expected.y, 1e-6 * length(expected));
  EXPECT_NEAR(on_magnet.z, expected.z, 1e-6 * length(expected));
  EXPECT_GT(length(expected), 1e-3);  // a real force, not 0 = 0
}

TEST(FluxLinkage, TheRateIsTheFluxsDerivativeAlongTheMotion) {
  // The magnet moves and spins, the coil moves and spins: the rate must be
  // the derivative of the flux of the moved configuration.
  const Vec3 m_centre{0.06, -0.01, 0}, m_axis = unit(Vec3{1, 0.4, 0});
  const Vec3 v_m{-0.8, 0.3, 0.1}, w_m{0, 0, 12}, v_c{0.1, 0.2, 0}, w_c{0, 0, -3};
  const double d = 0.017, q = 100;
  auto configuration = [&](double t, std::vector<Pole>& poles, std::vector<Vec3>& velocity,
                           CoilGeometry& coil) {
    const Vec3 centre = m_centre + v_m * t;
    const Vec3 axis =
        unit(m_axis + cross(w_m, m_axis) * t + cross(w_m, cross(w_m, m_axis)) * (t * t / 2));
    poles = bar(centre, axis, d, q, 1);
    velocity = {v_m + cross(w_m, poles[0].position - centre),
                v_m + cross(w_m, poles[1].position - centre)};
    const Vec3 c_axis0{1, 0, 0};
    coil = coil_at(v_c * t, unit(c_axis0 + cross(w_c, c_axis0) * t +
                                 cross(w_c, cross(w_c, c_axis0)) * (t * t / 2)));
    coil.velocity = v_c;
    coil.angular_velocity = w_c;
  };
  std::vector<Pole> poles;
  std::vector<Vec3> velocity;
  CoilGeometry coil;
  configuration(0, poles, velocity, coil);
  const FluxLinkage now = coil_flux(poles, velocity, kEps, coil);
  const double h = 1e-6;
  configuration(h, poles, velocity, coil);
  const double after = coil_flux(poles, velocity, kEps, coil).flux;
  configuration(-h, poles, velocity, coil);
  const double before = coil_flux(poles, velocity, kEps, coil).flux;
  const double numeric = (after - before) / (2 * h);
  EXPECT_NEAR(now.rate, numeric, 1e-5 * std::abs(numeric));
  EXPECT_GT(std::abs(numeric), 0.01);
}

TEST(FluxLinkage, AUniformFieldAlongTheCoilGivesNABAndItsOwnPolesDoNotCount) {
  // Far poles make a nearly uniform field B along x over the coil: Phi = k N d B_x
  // (k = A / d: N A B). The coil's own poles (its body) are skipped.
  const double big = 1e6, r = 100;  // a pole of 1e6 A m 100 m away on -x: B = mu0 q / (4 pi r^2)
  std::vector<Pole> poles = {{{-r, 0, 0}, big, 1}, {{0.01, 0, 0}, 5e3, 7}};
  CoilGeometry coil = coil_at({0, 0, 0}, {1, 0, 0});
  const double b = kMu0Over4Pi * big / (r * r);
  const FluxLinkage f = coil_flux(poles, {}, kEps, coil);
  EXPECT_NEAR(f.flux, coil.linkage * coil.separation * b,
              1e-6 * coil.linkage * coil.separation * b);
  EXPECT_EQ(f.rate, 0.0);  // nothing moves
}

}  // namespace
}  // namespace alloy::magnetism
