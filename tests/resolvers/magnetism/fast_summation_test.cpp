// Tests for issue 16's fast summation of pole forces: the SIMD direct kernel
// (every kernel this CPU runs against the scalar one, including a source at
// the target, coincident sources without softening, and a target's own
// group), the blocked tree against the direct sum within the tolerance on
// random, packed and clustered magnets with coincident and very close poles,
// the tolerance setting, the tree's refit between steps, and that few poles
// still take the scalar pair loop whose bits the golden hashes hold.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "resolvers/common/direct_kernel.hpp"
#include "resolvers/common/multipole_tree.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "tests/resolvers/magnetism/magnet_layouts.hpp"

namespace alloy::magnetism {
namespace {

struct Bars {
  std::vector<Pole> poles;
  void add(Vec3 centre, Vec3 axis, double separation, double q) {
    const auto b = std::uint32_t(poles.size() / 2);
    const BarPoles p = bar_poles(centre, axis / length(axis), separation);
    poles.push_back({p.north, q, b});
    poles.push_back({p.south, -q, b});
  }
};

using layouts::random_direction;

/// The shared layouts (magnet_layouts.hpp) as poles.
Bars as_bars(const std::vector<layouts::Bar>& placed) {
  Bars bars;
  for (const layouts::Bar& b : placed)
    bars.add(b.centre, b.axis, layouts::kBarSeparation, b.strength);
  return bars;
}
Bars random_bars(int n, std::uint64_t seed) {
  return as_bars(layouts::random_bars(std::size_t(n), seed));
}

/// Clusters of 40 bars (Gaussian, sigma 5 cm) a metre apart: dense lumps in
/// empty space, the case where cells are very unequal.
Bars clustered_bars(int clusters, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 0.05);
  std::uniform_real_distribution<double> u(0, 1);
  Bars bars;
  for (int k = 0; k < clusters; ++k) {
    const Vec3 c{double(k % 4), double(k / 4 % 4), double(k / 16)};
    for (int i = 0; i < 40; ++i)
      bars.add(c + Vec3{g(rng), g(rng), g(rng)}, random_direction(rng), 0.085, 50 + 100 * u(rng));
  }
  return bars;
}

Bars packed_bars(int nx, int ny, int nz) {
  return as_bars(layouts::packed_bars(nx, ny, nz));
}

std::vector<Vec3> bar_forces(const Bars& bars, const SummationOptions& o) {
  std::vector<Vec3> pf(bars.poles.size());
  accumulate_pole_forces(bars.poles, 0.005, pf, o);
  std::vector<Vec3> f(bars.poles.size() / 2);
  for (std::size_t i = 0; i < pf.size(); ++i) f[bars.poles[i].body] += pf[i];
  return f;
}

double rms_relative(const std::vector<Vec3>& approx, const std::vector<Vec3>& exact) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    num += dot(approx[i] - exact[i], approx[i] - exact[i]);
    den += dot(exact[i], exact[i]);
  }
  return std::sqrt(num / den);
}

/// The error of the tree at `tolerance` against the direct sum.
double tree_error(const Bars& bars, double tolerance) {
  const auto exact = bar_forces(bars, {.method = Summation::Direct});
  const auto approx =
      bar_forces(bars, {.method = Summation::Tree, .theta = theta_for_tolerance(tolerance)});
  for (const Vec3& f : approx) EXPECT_TRUE(is_finite(f));
  return rms_relative(approx, exact);
}

// --- the direct kernel ----------------------------------------------------------

struct Soa {
  std::vector<double> x, y, z, q, g;
  void add(Vec3 p, double strength, double group) {
    x.push_back(p.x), y.push_back(p.y), z.push_back(p.z), q.push_back(strength), g.push_back(group);
  }
};

TEST(DirectKernel, EveryKernelOnThisCpuMatchesTheScalarOne) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  Soa s;
  for (int i = 0; i < 203; ++i) s.add({u(rng), u(rng), u(rng)}, 10 * u(rng), double(i / 2));
  s.add({s.x[5], s.y[5], s.z[5]}, 7, 500);  // coincident with source 5, another group
  // Targets: the sources themselves (own position and own group left out),
  // 37 of them: not a multiple of any lane count.
  const std::size_t n = 37;
  std::vector<double> tg(s.g.begin(), s.g.begin() + n);
  for (double eps2 : {0.0, 1e-4}) {
    std::vector<double> ref[3];
    for (auto& r : ref) r.assign(n, 0.0);
    const multipole::SoaSources src{s.x.data(), s.y.data(), s.z.data(),
                                    s.q.data(), s.g.data(), s.x.size()};
    ASSERT_TRUE(multipole::direct_accumulate_with("scalar",
                                                  {s.x.data(), s.y.data(), s.z.data(), tg.data(),
                                                   ref[0].data(), ref[1].data(), ref[2].data(), n},
                                                  src, eps2));
    for (int i = 0; i < int(n); ++i) EXPECT_TRUE(std::isfinite(ref[0][i])) << i;
    for (const char* isa : {"avx2", "avx512"}) {
      std::vector<double> f[3];
      for (auto& r : f) r.assign(n, 0.0);
      if (!multipole::direct_accumulate_with(isa,
                                             {s.x.data(), s.y.data(), s.z.data(), tg.data(),
                                              f[0].data(), f[1].data(), f[2].data(), n},
                                             src, eps2)) {
        std::printf("%s: not on this CPU\n", isa);
        continue;
      }
      for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(f[c][i], ref[c][i], 1e-12 * std::abs(ref[c][i]) + 1e-9)
              << isa << " target " << i << " eps2 " << eps2;
    }
  }
}

TEST(DirectKernel, OwnGroupAndOwnPositionContributeNothing) {
  Soa s;
  s.add({0, 0, 0}, 5, 1);   // the target itself
  s.add({1, 0, 0}, -5, 1);  // its partner
  s.add({0, 2, 0}, 3, 2);   // another part: the only one that acts
  double x = 0, y = 0, z = 0, g = 1, fx = 0, fy = 0, fz = 0;
  multipole::direct_accumulate({&x, &y, &z, &g, &fx, &fy, &fz, 1},
                               {s.x.data(), s.y.data(), s.z.data(), s.q.data(), s.g.data(), 3},
                               0.0);
  EXPECT_DOUBLE_EQ(fx, 0.0);
  EXPECT_NEAR(fy, 3 * -2 / 8.0, 1e-15);  // q r / |r|^3 with r = (0, -2, 0)
  EXPECT_DOUBLE_EQ(fz, 0.0);
}

TEST(DirectKernel, SimdDirectPathMatchesThePairLoop) {
  // From kSimdDirectPoles poles the direct sum runs on the SIMD kernel; it
  // must agree with the scalar pair loop to rounding.
  const Bars bars = random_bars(400, 5);
  ASSERT_GE(bars.poles.size(), kSimdDirectPoles);
  std::vector<Vec3> simd(bars.poles.size()), pairs(bars.poles.size());
  accumulate_pole_forces(bars.poles, 0.005, simd, {.method = Summation::Direct});
  for (std::size_t i = 0; i < bars.poles.size(); ++i)
    for (std::size_t j = i + 1; j < bars.poles.size(); ++j) {
      if (bars.poles[i].body == bars.poles[j].body) continue;
      const Vec3 f = pole_pair_force(bars.poles[i].strength, bars.poles[i].position,
                                     bars.poles[j].strength, bars.poles[j].position, 0.005);
      pairs[j] += f;
      pairs[i] -= f;
    }
  EXPECT_LT(rms_relative(simd, pairs), 1e-13);
}

TEST(DirectKernel, FewPolesKeepTheScalarPairLoopsBits) {
  // The bundled scenes (a few magnets) must keep their golden hashes: below
  // kSimdDirectPoles the sum is the pair loop, bit for bit, under any method
  // that resolves to direct.
  const Bars bars = random_bars(20, 9);
  ASSERT_LT(bars.poles.size(), kSimdDirectPoles);
  std::vector<Vec3> direct(bars.poles.size()), automatic(bars.poles.size()),
      pairs(bars.poles.size());
  accumulate_pole_forces(bars.poles, 0.005, direct, {.method = Summation::Direct});
  accumulate_pole_forces(bars.poles, 0.005, automatic, {.method = Summation::Auto});
  for (std::size_t i = 0; i < bars.poles.size(); ++i)
    for (std::size_t j = i + 1; j < bars.poles.size(); ++j) {
      if (bars.poles[i].body == bars.poles[j].body) continue;
      const Vec3 f = pole_pair_force(bars.poles[i].strength, bars.poles[i].position,
                                     bars.poles[j].strength, bars.poles[j].position, 0.005);
      pairs[j] += f;
      pairs[i] -= f;
    }
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_EQ(direct[i], pairs[i]) << i;
    EXPECT_EQ(automatic[i], pairs[i]) << i;
  }
}

// --- the tree within its tolerance ------------------------------------------------

TEST(FastSummation, RandomMagnetsWithinTheTolerance) {
  const Bars bars = random_bars(1500, 21);
  const double e = tree_error(bars, 1e-3);
  std::printf("random 1,500 bars, tolerance 1e-3: RMS relative error %.2e\n", e);
  EXPECT_LT(e, 1e-3);
}

TEST(FastSummation, PackedMagnetsWithinTheTolerance) {
  const Bars bars = packed_bars(12, 10, 10);
  for (double tol : {1e-2, 1e-3, 1e-4}) {
    const double e = tree_error(bars, tol);
    std::printf("packed 1,200 bars, tolerance %.0e: RMS relative error %.2e\n", tol, e);
    EXPECT_LT(e, tol);
  }
}

TEST(FastSummation, ClusteredMagnetsWithinTheTolerance) {
  const Bars bars = clustered_bars(32, 4);
  const double e = tree_error(bars, 1e-3);
  std::printf("32 clusters of 40 bars: RMS relative error %.2e\n", e);
  EXPECT_LT(e, 1e-3);
}

TEST(FastSummation, CoincidentAndVeryClosePolesStayFiniteAndWithinTheTolerance) {
  Bars bars = random_bars(800, 8);
  // Two bars exactly on top of each other, one 1 nm off another, one 1 um
  // off a third, and a bar whose north pole sits on another bar's south pole.
  const auto copy = [&](std::size_t b, Vec3 shift) {
    const Pole& n = bars.poles[2 * b];
    const Pole& s = bars.poles[2 * b + 1];
    bars.add((n.position + s.position) * 0.5 + shift, n.position - s.position, 0.085, n.strength);
  };
  copy(3, {});
  copy(10, {1e-9, 0, 0});
  copy(20, {0, 1e-6, 0});
  {
    const Pole& s = bars.poles[2 * 30 + 1];
    bars.add(s.position + Vec3{0.0425, 0, 0}, {1, 0, 0}, 0.085, 80);
  }
  const double e = tree_error(bars, 1e-3);
  std::printf("800 random bars with coincident and close poles: RMS relative error %.2e\n", e);
  EXPECT_LT(e, 1e-3);
  // Without softening as well: finite, since coincident sources are skipped.
  std::vector<Vec3> pf(bars.poles.size());
  accumulate_pole_forces(bars.poles, 0.0, pf, {.method = Summation::Tree});
  for (const Vec3& f : pf) EXPECT_TRUE(is_finite(f));
}

TEST(FastSummation, ToleranceSetsTheta) {
  EXPECT_DOUBLE_EQ(theta_for_tolerance(kDefaultTolerance), kDefaultTheta);
  double last = 0;
  for (double tol : {1e-5, 1e-4, 1e-3, 1e-2, 1e-1}) {
    const double t = theta_for_tolerance(tol);
    EXPECT_GE(t, last);
    EXPECT_GT(t, 0);
    EXPECT_LT(t, 1);
    last = t;
  }
  EXPECT_LT(theta_for_tolerance(1e-4), theta_for_tolerance(1e-2));
}

TEST(FastSummation, RefitBetweenStepsStaysWithinTheTolerance) {
  Bars bars = random_bars(1500, 12);
  std::vector<multipole::Source> s;
  for (const Pole& p : bars.poles) s.push_back({p.position, p.strength, p.body});
  multipole::Tree tree;
  const multipole::TreeOptions o{.theta = kDefaultTheta, .reuse = true};
  tree.build(s, 0.005, o);
  EXPECT_FALSE(tree.refitted());
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0, 0.002);  // 2 mm moves: a few steps of a fast part
  for (int step = 0; step < 3; ++step) {
    for (std::size_t b = 0; b < s.size(); b += 2) {
      const Vec3 d{g(rng), g(rng), g(rng)};
      s[b].position += d, s[b + 1].position += d;
    }
    tree.build(s, 0.005, o);
    EXPECT_TRUE(tree.refitted()) << step;
    std::vector<Vec3> k(s.size()), exact(s.size());
    tree.evaluate_at_sources(k);
    multipole::direct_at_sources(s, 0.005, exact);
    std::vector<Vec3> fa(s.size() / 2), fe(s.size() / 2);
    for (std::size_t i = 0; i < s.size(); ++i) {
      fa[s[i].group] += k[i] * s[i].strength;
      fe[s[i].group] += exact[i] * s[i].strength;
    }
    EXPECT_LT(rms_relative(fa, fe), 1e-3) << step;
  }
  // A big move (every bar thrown across the cube): rebuilt.
  for (auto& src : s) src.position = src.position * -3.0;
  tree.build(s, 0.005, o);
  EXPECT_FALSE(tree.refitted());
  // Another set of sources (one fewer): rebuilt too.
  s.pop_back(), s.pop_back();
  tree.build(s, 0.005, o);
  EXPECT_FALSE(tree.refitted());
}

}  // namespace
}  // namespace alloy::magnetism
