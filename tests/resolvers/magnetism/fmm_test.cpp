// Tests for the fast multipole method (resolvers/common/fmm.hpp), through
// multipole::Fmm, the tree's FMM mode and pole_model's Summation::Fmm, against
// direct summation: random, packed and clustered sources, coincident and very
// close poles, a magnet longer than the cells, torques, the error's fall with
// the order and bit-identical repeats (gravity.nbody's use of it:
// tests/resolvers/gravity/nbody_gravity_test.cpp).
#include "resolvers/common/fmm.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "resolvers/common/multipole_tree.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "runtime/math.hpp"

namespace alloy::multipole {
namespace {

/// Magnets as sources: group b has sources 2b (+q) and 2b + 1 (-q).
struct Magnets {
  std::vector<Source> s;
  std::vector<Vec3> centre;
  void add(Vec3 c, Vec3 axis, double separation, double q) {
    const auto g = std::uint32_t(centre.size());
    const Vec3 half = axis * (0.5 * separation / length(axis));
    s.push_back({c + half, q, g});
    s.push_back({c - half, -q, g});
    centre.push_back(c);
  }
};

/// n kit bars (8.5 cm, 50 to 150 A*m, either sign) at random places, one per
/// (0.15 m)^3, pointing anywhere.
Magnets random_magnets(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double side = 0.15 * std::cbrt(double(n));
  Magnets m;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 c{side * u(rng), side * u(rng), side * u(rng)};
    const double z = 2 * u(rng) - 1, phi = 2 * std::numbers::pi * u(rng);
    const double s = std::sqrt(1 - z * z);
    m.add(c, {s * std::cos(phi), s * std::sin(phi), z}, 0.085,
          (50 + 100 * u(rng)) * (u(rng) < 0.5 ? -1 : 1));
  }
  return m;
}

/// 10 cm bars packed end to end and side by side, all along x: near poles
/// nearly cancel, and each bar's net force is a small difference.
Magnets packed_magnets(int nx, int ny, int nz) {
  Magnets m;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) m.add({0.1 * i, 0.02 * j, 0.02 * k}, {1, 0, 0}, 0.085, 100);
  return m;
}

std::vector<Vec3> direct(const std::vector<Source>& s, double eps) {
  std::vector<Vec3> out(s.size());
  direct_at_sources(s, eps, out);
  return out;
}

std::vector<Vec3> fmm(const std::vector<Source>& s, double eps, FmmOptions o) {
  Fmm f;
  f.build(s, eps, o);
  std::vector<Vec3> out(s.size());
  f.evaluate_at_sources(out);
  return out;
}

/// Net force on each magnet (q times the field at each pole, summed).
std::vector<Vec3> net(const Magnets& m, const std::vector<Vec3>& field) {
  std::vector<Vec3> f(m.centre.size());
  for (std::size_t i = 0; i < m.s.size(); ++i) f[m.s[i].group] += field[i] * m.s[i].strength;
  return f;
}

/// Torque on each magnet about its centre.
std::vector<Vec3> torque(const Magnets& m, const std::vector<Vec3>& field) {
  std::vector<Vec3> t(m.centre.size());
  for (std::size_t i = 0; i < m.s.size(); ++i) {
    const std::uint32_t g = m.s[i].group;
    t[g] += cross(m.s[i].position - m.centre[g], field[i] * m.s[i].strength);
  }
  return t;
}

double rms_relative(const std::vector<Vec3>& approx, const std::vector<Vec3>& exact) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    const Vec3 e = approx[i] - exact[i];
    num += dot(e, e);
    den += dot(exact[i], exact[i]);
  }
  return std::sqrt(num / den);
}

bool all_finite(const std::vector<Vec3>& v) {
  for (const Vec3& x : v)
    if (!is_finite(x)) return false;
  return true;
}

TEST(Fmm, RandomMagnetsForcesAndTorquesWithinTheBoundOfTheDefaults) {
  // pole_model's defaults (theta 0.6, order 4, leaves of 64) on 2,000
  // magnets: enough for thousands of cell-to-cell translations.
  const Magnets m = random_magnets(2000, 3);
  const auto exact = direct(m.s, 0.005);
  Fmm f;
  f.build(m.s, 0.005,
          {.theta = magnetism::kFmmTheta, .order = magnetism::kFmmOrder, .leaf_size = 64});
  std::vector<Vec3> approx(m.s.size());
  f.evaluate_at_sources(approx);
  const double ef = rms_relative(net(m, approx), net(m, exact));
  const double et = rms_relative(torque(m, approx), torque(m, exact));
  std::printf("random 2000 magnets, defaults: force %.2e, torque %.2e, %llu translations\n", ef, et,
              static_cast<unsigned long long>(f.cell_interactions()));
  EXPECT_LT(ef, 1e-3);
  EXPECT_LT(et, 1e-3);
  EXPECT_GT(f.cell_interactions(), 1000u);  // the expansions were used
}

TEST(Fmm, ErrorFallsWithTheOrder) {
  // Orders 1 and 2 give a field constant over a cell, so no net force on a
  // magnet from far cells; from 3 on each order roughly halves the error.
  const Magnets m = random_magnets(1500, 5);
  const auto exact = net(m, direct(m.s, 0.005));
  auto error = [&](int p) {
    return rms_relative(net(m, fmm(m.s, 0.005, {.theta = 0.5, .order = p, .leaf_size = 32})),
                        exact);
  };
  double previous = error(2);
  for (int p : {3, 4, 5, 6}) {
    const double e = error(p);
    std::printf("order %d: %.2e\n", p, e);
    EXPECT_LT(e, 0.75 * previous) << "order " << p;
    previous = e;
  }
  EXPECT_LT(previous, 2e-4);
}

TEST(Fmm, PackedBlockWithinItsMeasuredSettings) {
  // The hard case: net forces are small differences of large pole forces.
  // theta 0.4 and order 6 give 4.8e-4 on the bench's 25 x 20 x 20 block.
  const Magnets m = packed_magnets(12, 8, 8);
  const auto exact = direct(m.s, 0.005);
  const auto approx = fmm(m.s, 0.005, {.theta = 0.4, .order = 6, .leaf_size = 16});
  const double ef = rms_relative(net(m, approx), net(m, exact));
  const double et = rms_relative(torque(m, approx), torque(m, exact));
  std::printf("packed 768 bars, theta 0.4, order 6: force %.2e, torque %.2e\n", ef, et);
  EXPECT_LT(ef, 1e-3);
  EXPECT_LT(et, 1e-3);
}

TEST(Fmm, ClusteredMassesAgreeWithTheDirectSum) {
  // A dense Gaussian core and a sparse halo, no softening, no groups: deep
  // and uneven tree.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0, 1);
  std::vector<Source> s;
  for (int i = 0; i < 3000; ++i) {
    const double r = (i % 10 == 0) ? 20.0 : 1.0;
    s.push_back({{r * g(rng), r * g(rng), r * g(rng)}, 1.0 + (i % 7)});
  }
  const auto exact = direct(s, 0.0);
  const double e = rms_relative(fmm(s, 0.0, {.theta = 0.5, .order = 4, .leaf_size = 16}), exact);
  std::printf("clustered 3000 masses: %.2e\n", e);
  EXPECT_LT(e, 1e-3);
}

TEST(Fmm, CoincidentAndVeryClosePolesMatchTheDirectSum) {
  // Magnets whose poles sit exactly on other magnets' poles, magnets 1e-9 m
  // apart, and a pile of 100 magnets at one place (deeper than the tree's
  // depth limit can separate): every field finite and as the direct sum's.
  Magnets m = random_magnets(300, 9);
  for (int i = 0; i < 40; ++i) {
    const Vec3 at = m.s[std::size_t(2 * i)].position;
    m.add(at + Vec3{0.0425, 0, 0}, {1, 0, 0}, 0.085, 80);  // south pole exactly on another's pole
    m.add(at + Vec3{1e-9, 0, 0}, {0, 1, 0}, 0.085, -60);   // a centre 1e-9 m from that pole
  }
  for (int i = 0; i < 100; ++i) m.add({0.3, 0.3, 0.3}, {0, 0, 1}, 0.085, 70);
  for (double eps : {0.0, 0.005}) {
    const auto exact = direct(m.s, eps);
    const auto approx = fmm(m.s, eps, {.theta = 0.5, .order = 5, .leaf_size = 64});
    ASSERT_TRUE(all_finite(approx)) << "eps " << eps;
    const double e = rms_relative(net(m, approx), net(m, exact));
    std::printf("coincident and close poles, eps %g: %.2e\n", eps, e);
    EXPECT_LT(e, 1e-3) << "eps " << eps;
  }
}

TEST(Fmm, AMagnetLongerThanTheCellsNeverFeelsItself) {
  // Bars 3 m long among short ones in a 2 m cube: their two poles land in
  // far apart cells, which the expansions then see as separated. The tree is
  // built over whole magnets, so no cell pair used whole shares one.
  Magnets m = random_magnets(500, 13);
  for (int i = 0; i < 5; ++i) m.add({0.6 + 0.1 * i, 0.6, 0.6}, {1, 0.2 * i, 0}, 3.0, 200);
  const auto exact = direct(m.s, 0.005);
  const auto approx = fmm(m.s, 0.005, {.theta = 0.5, .order = 5, .leaf_size = 32});
  // Per pole, not only per magnet: a partner pole's pull is internal to the
  // magnet (it cancels in the net force and, being along the axis, in the
  // torque), so only the poles' own fields show whether it was left out.
  for (std::size_t i = 1000; i < m.s.size(); ++i)
    EXPECT_LT(length(approx[i] - exact[i]), 1e-3 * length(exact[i])) << "pole " << i;
  EXPECT_LT(rms_relative(approx, exact), 1e-3);
  const auto fe = net(m, exact), fa = net(m, approx);
  for (std::size_t g = 500; g < 505; ++g)
    EXPECT_LT(length(fa[g] - fe[g]), 1e-3 * length(fe[g])) << "long magnet " << g;
  EXPECT_LT(rms_relative(fa, fe), 1e-3);
}

TEST(Fmm, RepeatsAreBitIdenticalAndTheTreeModeIsTheSame) {
  const Magnets m = random_magnets(700, 17);
  const FmmOptions o{.theta = 0.6, .order = 4, .leaf_size = 32};
  const auto a = fmm(m.s, 0.005, o), b = fmm(m.s, 0.005, o);
  Tree tree;
  tree.build(m.s, 0.005, {.theta = 0.6, .leaf_size = 32, .fmm_order = 4});
  std::vector<Vec3> c(m.s.size());
  tree.evaluate_at_sources(c);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i], b[i]) << i;
    EXPECT_EQ(a[i], c[i]) << i;
  }
  // The tree in FMM mode answers single points exactly (by the direct sum).
  const Vec3 x{0.2, 0.3, 0.4};
  const Vec3 e = direct_sum(m.s, 0.005, x, 3);
  EXPECT_EQ(tree.evaluate(x, 3), e);
}

TEST(Fmm, PoleModelFmmMethodAgreesWithDirect) {
  using namespace alloy::magnetism;
  const Magnets m = random_magnets(400, 21);
  std::vector<Pole> poles;
  for (const Source& s : m.s) poles.push_back({s.position, s.strength, s.group});
  std::vector<Vec3> fd(poles.size()), ff(poles.size());
  accumulate_pole_forces(poles, 0.005, fd, {.method = Summation::Direct});
  accumulate_pole_forces(poles, 0.005, ff, {.method = Summation::Fmm, .theta = kFmmTheta});
  std::vector<Vec3> nd(m.centre.size()), nf(m.centre.size());
  for (std::size_t i = 0; i < poles.size(); ++i)
    nd[poles[i].body] += fd[i], nf[poles[i].body] += ff[i];
  EXPECT_LT(rms_relative(nf, nd), 1e-3);
}

}  // namespace
}  // namespace alloy::multipole
