// Tests for the fast multipole method (resolvers/common/fmm.hpp), through
// multipole::Fmm, the tree's FMM mode and pole_model's Summation::Fmm, against
// direct summation: random, packed and clustered sources, coincident and very
// close poles, a magnet longer than the cells, torques, the error's fall with
// the order and bit-identical repeats (gravity.nbody's use of it:
// tests/resolvers/gravity/nbody_gravity_test.cpp).
#include "resolvers/common/fmm.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "resolvers/common/direct_kernel.hpp"
#include "resolvers/common/multipole_tree.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "runtime/math.hpp"
#include "tests/resolvers/magnetism/magnet_layouts.hpp"

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

/// The shared layouts (magnet_layouts.hpp) as sources.
Magnets as_magnets(const std::vector<layouts::Bar>& bars) {
  Magnets m;
  for (const layouts::Bar& b : bars) m.add(b.centre, b.axis, layouts::kBarSeparation, b.strength);
  return m;
}
Magnets random_magnets(std::size_t n, std::uint64_t seed) {
  return as_magnets(layouts::random_bars(n, seed));
}
Magnets packed_magnets(int nx, int ny, int nz) {
  return as_magnets(layouts::packed_bars(nx, ny, nz));
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
  // pole_model's defaults (kFmmTheta, kFmmOrder, leaves of 64) on 2,000
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
  // Issue 16's goal is on the force (1e-3); the torque, a moment of the same
  // pole forces, measured 1.02e-3 here at the session-16 defaults (theta 0.7,
  // order 5), hence its bound of 1.5e-3.
  EXPECT_LT(ef, 1e-3);
  EXPECT_LT(et, 1.5e-3);
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

/// 300 random magnets, 40 with a magnet's south pole exactly on their pole
/// and 40 more centred 1e-9 m from it, and a pile of 100 magnets at one
/// place (deeper than the tree's depth limit can separate).
Magnets close_poles() {
  Magnets m = random_magnets(300, 9);
  for (int i = 0; i < 40; ++i) {
    const Vec3 at = m.s[std::size_t(2 * i)].position;
    m.add(at + Vec3{0.0425, 0, 0}, {1, 0, 0}, 0.085, 80);  // south pole exactly on another's pole
    m.add(at + Vec3{1e-9, 0, 0}, {0, 1, 0}, 0.085, -60);   // a centre 1e-9 m from that pole
  }
  for (int i = 0; i < 100; ++i) m.add({0.3, 0.3, 0.3}, {0, 0, 1}, 0.085, 70);
  return m;
}

TEST(Fmm, CoincidentAndVeryClosePolesMatchTheDirectSum) {
  // Magnets whose poles sit exactly on other magnets' poles, magnets 1e-9 m
  // apart, and a pile of 100 magnets at one place (deeper than the tree's
  // depth limit can separate): every field finite and as the direct sum's.
  const Magnets m = close_poles();
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

TEST(Fmm, BatchedTranslationsAndTheOnceEachNearFieldAgreeWithTheReference) {
  // Issue 16: the translations in SIMD batches and the near field summed
  // each pair once (both ways) against the reference paths (one translation
  // at a time; each way on its own), at every order: the same sums, so equal
  // to rounding, on magnets with coincident poles in the mix.
  Magnets m = random_magnets(600, 23);
  for (int i = 0; i < 10; ++i) m.add(m.s[std::size_t(2 * i)].position, {0, 0, 1}, 0.085, 90);
  const auto exact = direct(m.s, 0.005);
  for (int order = 1; order <= 2 * kMaxFmmOrder; ++order) {
    // Orders 1 to 6 with every pair at the full order, then again with each
    // pair at its own (pair_orders: the lists by order on the same paths).
    const FmmOptions fast{.theta = 0.7,
                          .order = (order - 1) % kMaxFmmOrder + 1,
                          .leaf_size = 16,
                          .pair_orders = order > kMaxFmmOrder};
    FmmOptions slow = fast;
    slow.m2l = FmmOptions::M2l::Reference;
    slow.mutual_near = false;
    FmmOptions one_lane = fast;
    one_lane.m2l = FmmOptions::M2l::Batched;
    const auto a = fmm(m.s, 0.005, fast), b = fmm(m.s, 0.005, slow), c = fmm(m.s, 0.005, one_lane);
    ASSERT_TRUE(all_finite(a)) << "order " << order;
    double worst = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double scale = length(exact[i]);
      worst = std::max({worst, length(a[i] - b[i]) / scale, length(c[i] - b[i]) / scale});
    }
    EXPECT_LT(worst, 1e-11) << "order " << order;
  }
}

TEST(Fmm, OnceEachNearKernelMatchesTheScalarReference) {
  // direct_accumulate_mutual (AVX-512 where the CPU has it) against its
  // scalar loop, with an odd number of targets (the wide kernel pairs them),
  // a source on a target (left out) and a shared group (left out).
  const Magnets m = random_magnets(37, 29);
  std::vector<double> x, y, z, q, g, tg;
  for (const Source& s : m.s)
    x.push_back(s.position.x), y.push_back(s.position.y), z.push_back(s.position.z),
        q.push_back(s.strength), g.push_back(double(s.group)), tg.push_back(double(s.group));
  const std::size_t nt = 31, n = x.size();   // targets: the first 31 poles; sources: all
  x[40] = x[3], y[40] = y[3], z[40] = z[3];  // a source exactly on target 3
  std::vector<double> first;                 // the wide kernel's sums
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<double> fx(nt), fy(nt), fz(nt), sx(n), sy(n), sz(n);
    const SoaTargets t{x.data(),  y.data(),  z.data(),  tg.data(),
                       fx.data(), fy.data(), fz.data(), nt};
    const SoaSources src{x.data(), y.data(), z.data(), q.data(), g.data(), n};
    if (pass == 0) {
      if (!direct_accumulate_mutual(t, q.data(), src, sx.data(), sy.data(), sz.data(), 1e-6))
        GTEST_SKIP() << "no wide once-each kernel on this CPU";
    } else {
      direct_accumulate_mutual_scalar(t, q.data(), src, sx.data(), sy.data(), sz.data(), 1e-6);
    }
    std::vector<double> all;
    for (auto* v : {&fx, &fy, &fz, &sx, &sy, &sz}) all.insert(all.end(), v->begin(), v->end());
    for (double v : all) ASSERT_TRUE(std::isfinite(v));
    if (pass == 0) {
      first = all;
      continue;
    }
    // The targets' sums against the one-way kernel, and every sum against the wide kernel's.
    std::vector<double> ox(nt), oy(nt), oz(nt);
    direct_accumulate(
        {x.data(), y.data(), z.data(), tg.data(), ox.data(), oy.data(), oz.data(), nt}, src, 1e-6);
    for (std::size_t i = 0; i < nt; ++i) EXPECT_NEAR(fx[i], ox[i], 1e-9 * std::abs(ox[i]) + 1e-9);
    double big = 0;
    for (double v : all) big = std::max(big, std::abs(v));
    for (std::size_t i = 0; i < all.size(); ++i) EXPECT_NEAR(first[i], all[i], 1e-12 * big) << i;
    // A source's sum: minus the targets' pulls on it (third law), e.g. source 40.
    double expect = 0;
    for (std::size_t i = 0; i < nt; ++i) {
      if (tg[i] == g[40]) continue;
      const double dx = x[i] - x[40], dy = y[i] - y[40], dz = z[i] - z[40];
      const double s2 = dx * dx + dy * dy + dz * dz + 1e-6;
      if (!(s2 > 1e-6)) continue;
      expect -= q[i] * dx / (s2 * std::sqrt(s2));
    }
    EXPECT_NEAR(sx[40], expect, 1e-12 * big);
  }
}

// --- the near field in single precision (FmmOptions::single_near) ---------------

/// Whether this CPU runs the single-precision near field at all (AVX-512).
bool has_single_kernel() {
  float x = 0, y = 0, z = 0, q = 1;
  std::int32_t g = -2, sg = -1;
  double f[3] = {};
  return direct_accumulate_single({&x, &y, &z, &g, f, f + 1, f + 2, 1}, {&x, &y, &z, &q, &sg, 1},
                                  1e-6f);
}

TEST(Fmm, SingleNearFieldWithinTheBoundOnRandomPackedAndClosePoles) {
  // The defaults with the near field in float, on random magnets, a packed
  // block and magnets with coincident and 1e-9 m poles (softening 5 mm): the
  // force against the direct sum within the bound, and against the same FMM
  // in double within 1e-5 (the float kernel's own error is far below the
  // expansions').
  const Magnets close = close_poles();
  struct Case {
    const char* name;
    Magnets m;
    FmmOptions o;
    double bound;
  };
  const FmmOptions defaults{
      .theta = magnetism::kFmmTheta, .order = magnetism::kFmmOrder, .leaf_size = 64};
  std::vector<Case> cases{
      {"random 1500", random_magnets(1500, 41), defaults, 1e-3},
      {"packed 10 x 8 x 8",
       packed_magnets(10, 8, 8),
       {.theta = 0.4, .order = 6, .leaf_size = 64},
       1e-3},
      {"coincident and close", close, {.theta = 0.5, .order = 5, .leaf_size = 64}, 1e-3}};
  for (Case& c : cases) {
    FmmOptions single = c.o;
    single.single_near = true;
    const auto exact = direct(c.m.s, 0.005);
    const auto twin = fmm(c.m.s, 0.005, c.o);
    Fmm f;
    f.build(c.m.s, 0.005, single);
    std::vector<Vec3> approx(c.m.s.size());
    f.evaluate_at_sources(approx);
    ASSERT_TRUE(all_finite(approx)) << c.name;
    const double e = rms_relative(net(c.m, approx), net(c.m, exact));
    const double d = rms_relative(net(c.m, approx), net(c.m, twin));
    std::printf("%s, single near field: error %.2e, against double %.2e, %llu of %llu pairs\n",
                c.name, e, d, static_cast<unsigned long long>(f.single_interactions()),
                static_cast<unsigned long long>(f.direct_interactions()));
    EXPECT_LT(e, c.bound) << c.name;
    EXPECT_LT(d, 1e-5) << c.name;
    if (has_single_kernel()) EXPECT_EQ(f.single_interactions(), f.direct_interactions()) << c.name;
  }
}

TEST(Fmm, SingleNearFieldFallsBackToDoubleWithoutSofteningOrWhenTheRegionIsTooLarge) {
  // No softening (1e-9 m pairs would be lost to float's rounding), or near
  // regions wider than kSingleNearReach softening lengths: the double path,
  // bit for bit.
  Magnets m = random_magnets(400, 43);
  for (int i = 0; i < 20; ++i)
    m.add(m.s[std::size_t(2 * i)].position + Vec3{1e-9, 0, 0}, {0, 1, 0}, 0.085, -60);
  for (double eps : {0.0, 1e-6}) {
    const FmmOptions o{.theta = 0.6, .order = 4, .leaf_size = 32};
    FmmOptions single = o;
    single.single_near = true;
    Fmm f;
    f.build(m.s, eps, single);
    std::vector<Vec3> a(m.s.size());
    f.evaluate_at_sources(a);
    const auto b = fmm(m.s, eps, o);
    EXPECT_EQ(f.single_interactions(), 0u) << "eps " << eps;
    for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "eps " << eps << " " << i;
  }
}

TEST(Fmm, SingleKernelsMatchTheScalarReference) {
  // direct_accumulate_single and its once-each form against the double
  // scalar loop, with an odd number of targets, 17 sources (a masked tail), a
  // source on a target and shared groups: the same sums to float's rounding.
  if (!has_single_kernel()) GTEST_SKIP() << "no single-precision kernel on this CPU";
  const Magnets m = random_magnets(20, 47);
  const std::size_t nt = 23, ns = 17;  // targets: poles 0..22; sources: poles 23..39
  std::vector<double> x, y, z, q, g, tg;
  for (const Source& s : m.s)
    x.push_back(s.position.x), y.push_back(s.position.y), z.push_back(s.position.z),
        q.push_back(s.strength), g.push_back(double(s.group)), tg.push_back(double(s.group));
  x[30] = x[4], y[30] = y[4], z[30] = z[4];  // a source exactly on target 4
  g[25] = tg[2];                             // a source in target 2's group
  std::vector<float> fx32, fy32, fz32, fq32;
  std::vector<std::int32_t> sg, tgi;
  for (std::size_t i = 0; i < x.size(); ++i)
    fx32.push_back(float(x[i])), fy32.push_back(float(y[i])), fz32.push_back(float(z[i])),
        fq32.push_back(float(q[i])), sg.push_back(std::int32_t(g[i])),
        tgi.push_back(std::int32_t(tg[i]));
  const double eps2 = 0.005 * 0.005;
  std::vector<double> rx(nt), ry(nt), rz(nt), sx(ns), sy(ns), sz(ns);
  const SoaSources src{x.data() + nt, y.data() + nt, z.data() + nt,
                       q.data() + nt, g.data() + nt, ns};
  direct_accumulate_mutual_scalar(
      {x.data(), y.data(), z.data(), tg.data(), rx.data(), ry.data(), rz.data(), nt}, q.data(), src,
      sx.data(), sy.data(), sz.data(), eps2);
  const SoaSourcesF srcf{fx32.data() + nt, fy32.data() + nt, fz32.data() + nt,
                         fq32.data() + nt, sg.data() + nt,   ns};
  for (bool mutual : {false, true}) {
    std::vector<double> ax(nt), ay(nt), az(nt);
    std::vector<float> bx(ns), by(ns), bz(ns);
    const SoaTargetsF t{fx32.data(), fy32.data(), fz32.data(), tgi.data(),
                        ax.data(),   ay.data(),   az.data(),   nt};
    if (mutual)
      ASSERT_TRUE(direct_accumulate_mutual_single(t, fq32.data(), srcf, bx.data(), by.data(),
                                                  bz.data(), float(eps2)));
    else
      ASSERT_TRUE(direct_accumulate_single(t, srcf, float(eps2)));
    double big = 0;
    for (std::size_t i = 0; i < nt; ++i)
      big = std::max({big, std::abs(rx[i]), std::abs(ry[i]), std::abs(rz[i])});
    for (std::size_t i = 0; i < nt; ++i) {
      EXPECT_NEAR(ax[i], rx[i], 1e-5 * big) << i;
      EXPECT_NEAR(ay[i], ry[i], 1e-5 * big) << i;
      EXPECT_NEAR(az[i], rz[i], 1e-5 * big) << i;
    }
    if (!mutual) continue;
    double sbig = 0;
    for (std::size_t j = 0; j < ns; ++j)
      sbig = std::max({sbig, std::abs(sx[j]), std::abs(sy[j]), std::abs(sz[j])});
    for (std::size_t j = 0; j < ns; ++j) {
      EXPECT_NEAR(bx[j], sx[j], 1e-5 * sbig) << j;
      EXPECT_NEAR(by[j], sy[j], 1e-5 * sbig) << j;
      EXPECT_NEAR(bz[j], sz[j], 1e-5 * sbig) << j;
    }
  }
}

TEST(Fmm, ReuseKeepsTheCellsAndListsWhileTheMagnetsMoveLittle) {
  // FmmOptions::reuse: the same positions again give the same bits, lists
  // and all; magnets moved 2 mm keep the cells (and, mostly, the lists) and
  // stay within the bound against the direct sum at their new places (the
  // translations that no longer meet the criterion walked again); a
  // change of groups, or a move that swells the cells, builds afresh.
  const Magnets m = random_magnets(1500, 51);
  const FmmOptions o{.theta = magnetism::kFmmTheta,
                     .order = magnetism::kFmmOrder,
                     .leaf_size = 64,
                     .single_near = true,
                     .reuse = true};
  Fmm f;
  f.build(m.s, 0.005, o);
  EXPECT_FALSE(f.reused());
  std::vector<Vec3> first(m.s.size()), again(m.s.size());
  f.evaluate_at_sources(first);
  f.build(m.s, 0.005, o);
  EXPECT_TRUE(f.reused());
  f.evaluate_at_sources(again);
  EXPECT_TRUE(f.lists_reused());
  for (std::size_t i = 0; i < first.size(); ++i) ASSERT_EQ(first[i], again[i]) << i;

  std::mt19937_64 rng(53);
  Magnets moved = m;
  std::vector<Vec3> shift(m.centre.size());
  for (Vec3& v : shift) v = layouts::random_direction(rng) * 0.002;
  for (Source& s : moved.s) s.position += shift[s.group];
  f.build(moved.s, 0.005, o);
  EXPECT_TRUE(f.reused());
  std::vector<Vec3> out(m.s.size());
  f.evaluate_at_sources(out);
  const double e = rms_relative(net(moved, out), net(moved, direct(moved.s, 0.005)));
  std::printf("reused cells, magnets moved 2 mm: error %.2e, lists reused %d\n", e,
              int(f.lists_reused()));
  EXPECT_LT(e, 1e-3);
  EXPECT_TRUE(f.lists_reused());

  Magnets regrouped = moved;
  std::swap(regrouped.s[0].group, regrouped.s[2].group);
  f.build(regrouped.s, 0.005, o);
  EXPECT_FALSE(f.reused());

  Magnets spread = m;
  for (Source& s : spread.s) s.position = s.position * 3.0;
  f.build(m.s, 0.005, o);
  f.build(spread.s, 0.005, o);
  EXPECT_FALSE(f.reused());
  f.evaluate_at_sources(out);
  EXPECT_FALSE(f.lists_reused());
  EXPECT_LT(rms_relative(net(spread, out), net(spread, direct(spread.s, 0.005))), 1e-3);
}

/// Magnets in eight Gaussian clusters (a tenth of the cube's side wide) in
/// the cube random_bars would fill, pointing anywhere.
Magnets clustered_magnets(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  const double side = 0.15 * std::cbrt(double(n));
  std::vector<Vec3> centres;
  for (int k = 0; k < 8; ++k) centres.push_back({side * u(rng), side * u(rng), side * u(rng)});
  Magnets m;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 c = centres[i % 8] + Vec3{g(rng), g(rng), g(rng)} * (0.1 * side);
    const Vec3 axis = layouts::random_direction(rng);
    m.add(c, axis, layouts::kBarSeparation, (50 + 100 * u(rng)) * (u(rng) < 0.5 ? -1 : 1));
  }
  return m;
}

TEST(Fmm, EachPairTakesTheLowestOrderItsSeparationAllows) {
  // Two bars along x, a distance d apart on their axis (the worst alignment
  // for the expansions): with leaves of one magnet the tree has two, centred
  // on the magnets with radius s / 2, so their one pair has rho = s / d. At
  // theta 0.7 and order 5, FmmOptions::pair_orders gives it the least q >= 2
  // with rho^(q-1) <= 0.7^4: limits 0.240, 0.490, 0.622 for q = 2, 3, 4.
  // Each bar's field at the other's poles then stays within the error the
  // full order makes at the separation limit (rho 0.69), which is what the
  // rule promises pair by pair.
  const double s = layouts::kBarSeparation, theta = 0.7;
  auto field_error = [&](double rho, bool pair_orders, int* order_used) {
    Magnets m;
    m.add({0, 0, 0}, {1, 0, 0}, s, 100);
    m.add({s / rho, 0, 0}, {1, 0, 0}, s, -80);
    Fmm f;
    f.build(m.s, 0.005, {.theta = theta, .order = 5, .leaf_size = 2, .pair_orders = pair_orders});
    std::vector<Vec3> out(m.s.size());
    f.evaluate_at_sources(out);
    const auto exact = direct(m.s, 0.005);
    EXPECT_EQ(f.cell_interactions(), 1u) << "rho " << rho;  // the one pair, translated
    for (int q = 1; q <= kMaxFmmOrder; ++q)
      if (f.translations_by_order()[std::size_t(q)] == 1) *order_used = q;
    return rms_relative(out, exact);
  };
  int full_order = 0;
  const double at_limit = field_error(0.69, false, &full_order);
  EXPECT_EQ(full_order, 5);
  std::printf("two bars, rho 0.69, order 5: field error %.2e\n", at_limit);
  const std::pair<double, int> cases[] = {{0.05, 2}, {0.1, 2}, {0.2, 2},  {0.3, 3},  {0.45, 3},
                                          {0.5, 4},  {0.6, 4}, {0.63, 5}, {0.65, 5}, {0.69, 5}};
  for (const auto& [rho, expected] : cases) {
    int used = 0;
    const double e = field_error(rho, true, &used);
    std::printf("rho %.2f: order %d, field error %.2e\n", rho, used, e);
    EXPECT_EQ(used, expected) << "rho " << rho;
    EXPECT_LE(e, at_limit) << "rho " << rho;
  }
}

TEST(Fmm, PairOrdersWithinTheBoundOnRandomPackedClusteredAndClosePoles) {
  // FmmOptions::pair_orders against the direct sum, and against the same
  // settings with every pair at the full order (measured: the lower orders
  // add 5 to 30 % to its error here, 70 % on the coincident poles, whose
  // error is a tenth of the bound): random magnets
  // at two sizes, Gaussian clusters, the packed block at its measured
  // settings, and the coincident and very close poles of the test above.
  struct Case {
    const char* name;
    Magnets m;
    FmmOptions o;
  };
  const FmmOptions defaults{
      .theta = magnetism::kFmmTheta, .order = magnetism::kFmmOrder, .leaf_size = 64};
  const Magnets close = close_poles();
  std::vector<Case> cases = {
      {"random 300", random_magnets(300, 1), defaults},
      {"random 2000", random_magnets(2000, 3), defaults},
      {"clustered 2000", clustered_magnets(2000, 1), defaults},
      {"packed 768", packed_magnets(12, 8, 8), {.theta = 0.4, .order = 6, .leaf_size = 16}},
      {"coincident and close", close, {.theta = 0.5, .order = 5, .leaf_size = 64}},
  };
  for (Case& c : cases) {
    const auto exact = net(c.m, direct(c.m.s, 0.005));
    const double full = rms_relative(net(c.m, fmm(c.m.s, 0.005, c.o)), exact);
    c.o.pair_orders = true;
    Fmm f;
    f.build(c.m.s, 0.005, c.o);
    std::vector<Vec3> out(c.m.s.size());
    f.evaluate_at_sources(out);
    ASSERT_TRUE(all_finite(out)) << c.name;
    const double e = rms_relative(net(c.m, out), exact);
    const auto& by = f.translations_by_order();
    std::uint64_t lower = 0;
    for (int q = 1; q < c.o.order; ++q) lower += by[std::size_t(q)];
    std::printf(
        "%s, pair orders: %.2e (every pair at order %d: %.2e); %llu of %llu translations "
        "below it\n",
        c.name, e, c.o.order, full, static_cast<unsigned long long>(lower),
        static_cast<unsigned long long>(f.cell_interactions()));
    EXPECT_LT(e, 1e-3) << c.name;
    EXPECT_LT(e, 2 * full) << c.name;
    EXPECT_GT(lower, 0u) << c.name;  // the lower orders were used
  }
}

TEST(Fmm, ProfileAccountsForEveryPhase) {
  const Magnets m = random_magnets(800, 31);
  Fmm f;
  f.build(m.s, 0.005, {.theta = 0.6, .order = 4, .leaf_size = 32});
  std::vector<Vec3> out(m.s.size());
  f.evaluate_at_sources(out);
  const FmmProfile& p = f.profile();
  for (double phase : {p.tree, p.upward, p.walk, p.m2l, p.near, p.downward}) EXPECT_GE(phase, 0);
  EXPECT_GT(p.near, 0);
  EXPECT_GT(p.m2l, 0);
  EXPECT_GT(f.cell_interactions(), 0u);
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
