// Tests for the Barnes-Hut summation of pole forces (resolvers/common/multipole_tree.hpp
// through pole_model.hpp and the magnetic_forces set): the cell expansion
// against the direct sum, the error bound on random and packed magnets,
// a magnet's own poles left out even inside a cell used whole, coincident
// poles, bit-identical repeats, and the set's method / theta settings.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "magnet_scene.hpp"
#include "resolvers/common/multipole_tree.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "tests/resolvers/magnetism/magnet_layouts.hpp"

namespace alloy::magnetism {
namespace {

using namespace testing;

/// Bars as poles: body b has poles 2b (north) and 2b + 1 (south).
struct Bars {
  std::vector<Pole> poles;
  std::size_t count() const { return poles.size() / 2; }
  void add(Vec3 centre, Vec3 axis, double separation, double q) {
    const auto b = std::uint32_t(count());
    const BarPoles p = bar_poles(centre, axis / length(axis), separation);
    poles.push_back({p.north, q, b});
    poles.push_back({p.south, -q, b});
  }
};

/// The shared layouts (tests/resolvers/magnetism/magnet_layouts.hpp) as poles.
Bars as_bars(const std::vector<layouts::Bar>& placed) {
  Bars bars;
  for (const layouts::Bar& b : placed)
    bars.add(b.centre, b.axis, layouts::kBarSeparation, b.strength);
  return bars;
}
Bars random_bars(std::size_t n, std::uint64_t seed) {
  return as_bars(layouts::random_bars(n, seed));
}
Bars packed_bars(int nx, int ny, int nz) {
  return as_bars(layouts::packed_bars(nx, ny, nz));
}

/// Force on each bar (sum over its two poles), N.
std::vector<Vec3> bar_forces(const Bars& bars, const SummationOptions& options,
                             double eps = 0.005) {
  std::vector<Vec3> pole_force(bars.poles.size());
  accumulate_pole_forces(bars.poles, eps, pole_force, options);
  std::vector<Vec3> f(bars.count());
  for (std::size_t b = 0; b < bars.count(); ++b) f[b] = pole_force[2 * b] + pole_force[2 * b + 1];
  return f;
}

/// The error measure of docs/magnetism.md: sqrt(sum |F_tree - F_direct|^2 /
/// sum |F_direct|^2) over the bars, i.e. RMS of the error over RMS of the force.
double rms_relative(const std::vector<Vec3>& approx, const std::vector<Vec3>& exact) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    const Vec3 e = approx[i] - exact[i];
    num += dot(e, e);
    den += dot(exact[i], exact[i]);
  }
  return std::sqrt(num / den);
}

const SummationOptions kDirect{.method = Summation::Direct};
SummationOptions tree(double theta) {
  return {.method = Summation::Tree, .theta = theta};
}

TEST(PoleTree, CellExpansionErrorFallsAsTheCubeOfSizeOverDistance) {
  // One cluster of signed sources seen from farther and farther away with
  // theta just under 1 (the cell is always taken whole): a second-order
  // expansion leaves an error of relative order (b / r)^3 against the field.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  std::vector<multipole::Source> sources;
  for (int i = 0; i < 40; ++i) sources.push_back({{u(rng), u(rng), u(rng)}, 10 * u(rng)});
  multipole::Tree t;
  t.build(sources, 0.0, {.theta = 0.99, .leaf_size = 64});
  double previous = 0;
  for (double r : {0.5, 1.0, 2.0, 4.0}) {
    const Vec3 x{r * 0.6, r * 0.8, 0};
    const Vec3 exact = multipole::direct_sum(sources, 0.0, x);
    const double err = length(t.evaluate(x) - exact) / length(exact);
    EXPECT_LT(err, 0.2 * std::pow(0.087 / r, 2)) << "r = " << r;
    if (previous > 0) {
      EXPECT_LT(err, previous / 5) << "halving b/r cuts the error by ~8 or more";
    }
    previous = err;
  }
  EXPECT_EQ(t.cell_interactions(), 4u) << "the root was used whole every time";
}

TEST(PoleTree, SofteningIsExpandedToo) {
  // With eps comparable to the distance, the expansion of the softened kernel
  // (not of 1/r^2) must still match the softened direct sum.
  std::vector<multipole::Source> sources = {
      {{0.01, 0, 0}, 3}, {{-0.01, 0.005, 0}, -2}, {{0, -0.01, 0.01}, 1.5}};
  multipole::Tree t;
  t.build(sources, 0.2, {.theta = 0.99, .leaf_size = 8});
  const Vec3 x{0.15, 0.1, -0.05};
  const Vec3 exact = multipole::direct_sum(sources, 0.2, x);
  EXPECT_LT(length(t.evaluate(x) - exact), 5e-5 * length(exact));
  EXPECT_EQ(t.cell_interactions(), 1u);
}

TEST(PoleTree, RandomMagnetsWithinTheErrorBound) {
  const Bars bars = random_bars(600, 1);
  const auto exact = bar_forces(bars, kDirect);
  const double e = rms_relative(bar_forces(bars, tree(kDefaultTheta)), exact);
  const double e5 = rms_relative(bar_forces(bars, tree(0.5)), exact);
  EXPECT_LT(e, 1e-3);
  EXPECT_LT(e, e5 / 4) << "a smaller opening angle is more accurate";
  EXPECT_GT(e, 0) << "the tree really approximated something";
  std::printf("random 600 bars: RMS relative error %.2e (theta %.2f), %.2e (theta 0.5)\n", e,
              kDefaultTheta, e5);
}

TEST(PoleTree, PackedMagnetsWithinTheErrorBound) {
  const Bars bars = packed_bars(12, 8, 6);  // 576 bars touching
  const auto exact = bar_forces(bars, kDirect);
  const double e = rms_relative(bar_forces(bars, tree(kDefaultTheta)), exact);
  EXPECT_LT(e, 1e-3);
  EXPECT_GT(e, 0);
  std::printf("packed 576 bars: RMS relative error %.2e (theta %.2f)\n", e, kDefaultTheta);
}

TEST(PoleTree, TorquesFollowTheForcesOnThePoles) {
  // Torque about each bar's centre from its two pole forces: same measure.
  const Bars bars = random_bars(300, 3);
  auto torques = [&](const SummationOptions& o) {
    std::vector<Vec3> pf(bars.poles.size());
    accumulate_pole_forces(bars.poles, 0.005, pf, o);
    std::vector<Vec3> t(bars.count());
    for (std::size_t b = 0; b < bars.count(); ++b) {
      const Vec3 c = (bars.poles[2 * b].position + bars.poles[2 * b + 1].position) * 0.5;
      t[b] = cross(bars.poles[2 * b].position - c, pf[2 * b]) +
             cross(bars.poles[2 * b + 1].position - c, pf[2 * b + 1]);
    }
    return t;
  };
  EXPECT_LT(rms_relative(torques(tree(kDefaultTheta)), torques(kDirect)), 1e-3);
}

TEST(PoleTree, OwnPolesLeftOutEvenInsideACellUsedWhole) {
  // The target pole's partner (same body) sits in a far cluster that the tree
  // takes whole: the partner must still not act on it.
  std::vector<multipole::Source> sources;
  sources.push_back({{0, 0, 0}, 5, 0});
  sources.push_back({{10, 0, 0}, -5, 0});  // the partner, far off
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  for (std::uint32_t i = 0; i < 30; ++i)
    sources.push_back({{10 + u(rng), u(rng), u(rng)}, 4 * u(rng), 1 + i});
  multipole::Tree t;
  t.build(sources, 0.005, {.theta = 0.5, .leaf_size = 4, .block = 2});
  std::vector<Vec3> at(sources.size());
  // At the sources, a block's sphere holds its groups' poles, so the partner
  // is never in a cell used whole (summed directly and left out by group).
  t.evaluate_at_sources(at);
  const Vec3 exact = multipole::direct_sum(sources, 0.005, {0, 0, 0}, 0);
  EXPECT_LT(length(at[0] - exact), 1e-6 * length(exact));
  // At one point, the cluster (partner included) is taken whole and the
  // partner taken out again.
  const std::uint64_t cells = t.cell_interactions();
  const Vec3 one = t.evaluate({0, 0, 0}, 0);
  EXPECT_GT(t.cell_interactions(), cells);
  EXPECT_LT(length(one - exact), 1e-6 * length(exact));
  // Had the partner been counted, the field would be ~5/100 instead of ~0.4/100.
  const Vec3 with_partner = multipole::direct_sum(sources, 0.005, {0, 0, 0});
  EXPECT_GT(length(with_partner - exact), 10 * length(at[0] - exact));
}

TEST(PoleTree, CoincidentPolesStayFiniteAndMatchTheDirectSum) {
  // Many poles at one point (magnets dropped in one place): the tree stops
  // splitting at its depth limit instead of recursing for ever.
  Bars bars;
  for (int i = 0; i < 40; ++i) bars.add({0, 0, 0}, {1, 0, 0}, 0.085, 10 + i);
  for (int i = 0; i < 40; ++i) bars.add({0.3, 0, 0}, {0, 1, 0}, 0.085, 10 + i);
  const auto exact = bar_forces(bars, kDirect);
  const auto approx = bar_forces(bars, tree(kDefaultTheta));
  for (const Vec3& f : approx) EXPECT_TRUE(is_finite(f));
  // Each cluster's own forces cancel exactly (its poles coincide), leaving the
  // small pull of the other: a looser bound than for spread-out magnets.
  EXPECT_LT(rms_relative(approx, exact), 1e-2);
}

TEST(PoleTree, RepeatedRunsAreBitIdentical) {
  const Bars bars = random_bars(500, 5);
  multipole::Tree workspace;
  auto run = [&] {
    std::vector<Vec3> f(bars.poles.size());
    accumulate_pole_forces(bars.poles, 0.005, f, tree(kDefaultTheta), &workspace);
    return f;
  };
  const auto a = run();
  const auto b = run();  // the workspace reused
  const auto c = bar_forces(bars, tree(kDefaultTheta));
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i], b[i]) << i;
  }
  for (std::size_t b2 = 0; b2 < c.size(); ++b2) EXPECT_EQ(a[2 * b2] + a[2 * b2 + 1], c[b2]);
}

TEST(PoleTree, FieldsAtPointsMatchTheDirectSum) {
  const Bars bars = random_bars(200, 9);
  std::vector<Vec3> points;
  std::vector<std::uint32_t> exclude;
  for (std::size_t b = 0; b < 100; ++b) {
    points.push_back(bars.poles[2 * b].position * 0.5 + bars.poles[2 * b + 1].position * 0.5);
    exclude.push_back(std::uint32_t(b));
  }
  std::vector<Vec3> exact(points.size()), approx(points.size());
  pole_fields(bars.poles, 0.005, points, exclude, exact, kDirect);
  pole_fields(bars.poles, 0.005, points, exclude, approx, tree(kDefaultTheta));
  EXPECT_LT(rms_relative(approx, exact), 1e-3);
}

TEST(PoleTree, AutoSwitchesAtTheCrossover) {
  EXPECT_FALSE((SummationOptions{.method = Summation::Auto}.use_tree(kTreeCrossoverPoles - 1)));
  EXPECT_TRUE((SummationOptions{.method = Summation::Auto}.use_tree(kTreeCrossoverPoles)));
  EXPECT_FALSE(kDirect.use_tree(1000000));
  EXPECT_TRUE(tree(kDefaultTheta).use_tree(2));
}

// --- the magnetic_forces set --------------------------------------------------------

class MagneticForcesMethod : public ::testing::Test {
 protected:
  void SetUp() override {
    register_current_source(registry);
    register_magnetism_resolver(registry);
  }
  WorldDef with(const char* method, double theta = kDefaultTheta) {
    WorldDef def;
    def.settings[MagneticForces::kName].set("method", std::string(method));
    def.settings[MagneticForces::kName].set("theta", theta);
    return def;
  }
  std::vector<Vec3> forces(WorldDef def, bool* used_tree = nullptr) {
    World w(registry, std::move(def));
    std::mt19937_64 rng(21);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 150; ++i)
      add_permanent(w, "m" + std::to_string(i), {2 * u(rng), 2 * u(rng), 2 * u(rng)},
                    2 * std::numbers::pi * u(rng), 50 + 100 * u(rng));
    w.start();
    const MagneticForces& f = forces_of(w);
    if (used_tree) *used_tree = f.used_tree();
    std::vector<Vec3> out;
    for (const MagneticBody& b : f.bodies()) out.push_back(b.force);
    return out;
  }
  PluginRegistry registry;
};

TEST_F(MagneticForcesMethod, TreeSettingAgreesWithDirect) {
  bool tree_used = false, direct_used = true, auto_used = true;
  const auto exact = forces(with("direct"), &direct_used);
  const auto approx = forces(with("tree", kDefaultTheta), &tree_used);
  const auto automatic = forces(WorldDef{}, &auto_used);
  EXPECT_FALSE(direct_used);
  EXPECT_TRUE(tree_used);
  EXPECT_FALSE(auto_used) << "300 poles are below the crossover";
  EXPECT_LT(rms_relative(approx, exact), 1e-3);
  EXPECT_EQ(automatic, exact);
}

TEST_F(MagneticForcesMethod, BadSettingsAreRefused) {
  EXPECT_THROW(forces(with("multipole")), InputError);
  // "fmm" is a method since session 15; its order must be whole, 1 to 6.
  EXPECT_NO_THROW(forces(with("fmm", kFmmTheta)));
  for (double bad : {0.0, 7.0, 2.5, -1.0, std::nan("")}) {
    WorldDef def = with("fmm", kFmmTheta);
    def.settings[MagneticForces::kName].set("order", bad);
    EXPECT_THROW(forces(def), InputError) << bad;
  }
  EXPECT_THROW(forces(with("tree", 1.0)), InputError);
  EXPECT_THROW(forces(with("tree", 0.0)), InputError);
  for (double bad : {0.0, 1e-6, 0.5, -1e-3, std::nan("")}) {
    WorldDef def;
    def.settings[MagneticForces::kName].set("tolerance", bad);
    EXPECT_THROW(forces(def), InputError) << bad;
  }
}

TEST_F(MagneticForcesMethod, ToleranceSetsThetaAndReuseIsASetting) {
  auto stage_of = [&](double tolerance, bool reuse) {
    WorldDef def;
    def.settings[MagneticForces::kName].set("method", std::string("tree"));
    def.settings[MagneticForces::kName].set("tolerance", tolerance);
    def.settings[MagneticForces::kName].set("reuse_tree", reuse);
    auto w = std::make_unique<World>(registry, std::move(def));
    add_permanent(*w, "a", {0, 0, 0}, 0, 100);
    add_permanent(*w, "b", {0.2, 0, 0}, 0, 100);
    w->start();
    return forces_of(*w).summation();
  };
  const SummationOptions fine = stage_of(1e-4, false), coarse = stage_of(1e-2, true);
  EXPECT_DOUBLE_EQ(fine.theta, theta_for_tolerance(1e-4));
  EXPECT_DOUBLE_EQ(coarse.theta, theta_for_tolerance(1e-2));
  EXPECT_LT(fine.theta, coarse.theta);
  EXPECT_FALSE(fine.reuse);
  EXPECT_TRUE(coarse.reuse);
  // With the tolerance, the tree's error on the set's magnets stays within it.
  for (double tol : {1e-2, 1e-4}) {
    WorldDef def;
    def.settings[MagneticForces::kName].set("method", std::string("tree"));
    def.settings[MagneticForces::kName].set("tolerance", tol);
    EXPECT_LT(rms_relative(forces(def), forces(with("direct"))), tol) << tol;
  }
}

// --- method "auto" (the default): the FMM with its check, else the tree ------------

/// The stage on bars of a layout (the bars' axis is the body's x).
struct LayoutStage {
  LayoutStage(PluginRegistry& registry, const std::vector<layouts::Bar>& bars, WorldDef def)
      : world(registry, std::move(def)) {
    int i = 0;
    for (const layouts::Bar& bar : bars) {
      const Vec3 a = bar.axis / length(bar.axis);
      const Vec3 about = cross({1, 0, 0}, a);
      const double s = length(about);
      const ObjectId id =
          add_permanent(world, "m" + std::to_string(i++), bar.centre, 0, bar.strength);
      if (s > 1e-12)
        world.set(id, prop::kOrientation, Quat::from_axis_angle(about / s, std::atan2(s, a.x)));
      else if (a.x < 0)
        world.set(id, prop::kOrientation, Quat::from_angle_z(std::numbers::pi));
    }
    world.start();
  }
  const MagneticForces& stage() const { return forces_of(const_cast<World&>(world)); }
  std::vector<Vec3> forces() const {
    std::vector<Vec3> out;
    for (const MagneticBody& b : stage().bodies()) out.push_back(b.force);
    return out;
  }
  World world;
};

WorldDef method(const char* m) {
  WorldDef def;
  def.settings[MagneticForces::kName].set("method", std::string(m));
  return def;
}

TEST_F(MagneticForcesMethod, AutoTakesTheFmmOnSpreadMagnetsWithinTheTolerance) {
  // 500 magnets, 1,000 poles: past kFmmAutoPoles, below the tree's crossover.
  static_assert(kFmmAutoPoles <= 1000 && 1000 < kTreeCrossoverPoles);
  const auto bars = layouts::random_bars(500, 3);
  const LayoutStage automatic(registry, bars, WorldDef{}), direct(registry, bars, method("direct"));
  EXPECT_EQ(automatic.stage().used_method(), Summation::Fmm);
  EXPECT_EQ(direct.stage().used_method(), Summation::Direct);
  const double error = rms_relative(automatic.forces(), direct.forces());
  EXPECT_LT(error, 1e-3);
  EXPECT_LE(automatic.stage().last_check_error(), 1e-3);
  EXPECT_TRUE(std::isnan(direct.stage().last_check_error()));
  // Below kFmmAutoPoles auto is the direct sum, bit for bit.
  const auto few = layouts::random_bars(kFmmAutoPoles / 2 - 1, 3);
  const LayoutStage few_auto(registry, few, WorldDef{}),
      few_direct(registry, few, method("direct"));
  EXPECT_EQ(few_auto.stage().used_method(), Summation::Direct);
  EXPECT_EQ(few_auto.forces(), few_direct.forces());
}

TEST_F(MagneticForcesMethod, AutoFallsBackWhereTheCheckFindsTheFmmOutsideTheTolerance) {
  // A packed block of aligned bars (640 magnets): the FMM at its defaults is
  // far outside 1e-3 there (near forces cancel), so auto sums directly
  // (1,280 poles, below the tree's crossover) and gets the direct sum's bits.
  const auto block = layouts::packed_bars(10, 8, 8);
  const LayoutStage automatic(registry, block, WorldDef{}),
      direct(registry, block, method("direct")), fmm(registry, block, method("fmm"));
  EXPECT_GT(rms_relative(fmm.forces(), direct.forces()), 1e-3) << "the case the check is for";
  EXPECT_GT(automatic.stage().last_check_error(), 1e-3);
  EXPECT_EQ(automatic.stage().used_method(), Summation::Direct);
  EXPECT_EQ(automatic.forces(), direct.forces());
  // A tolerance the FMM cannot meet on spread magnets either: the same.
  WorldDef strict;
  strict.settings[MagneticForces::kName].set("tolerance", 1e-5);
  const auto bars = layouts::random_bars(500, 3);
  const LayoutStage tight(registry, bars, strict), exact(registry, bars, method("direct"));
  EXPECT_EQ(tight.stage().used_method(), Summation::Direct);
  EXPECT_EQ(tight.forces(), exact.forces());
}

TEST_F(MagneticForcesMethod, AutoWithinTheToleranceOnClusteredCoincidentAndVeryClosePoles) {
  // Spread magnets, a tight cluster, two magnets at one place and pairs 1e-9 m
  // apart: whatever auto takes, its forces are within the tolerance.
  std::vector<layouts::Bar> bars = layouts::random_bars(420, 5);
  std::mt19937_64 rng(8);
  std::normal_distribution<double> g(0, 0.05);
  for (int i = 0; i < 60; ++i)
    bars.push_back(
        {Vec3{1, 1, 1} + Vec3{g(rng), g(rng), g(rng)}, layouts::random_direction(rng), 100});
  bars.push_back({{0.3, 0.3, 0.3}, {0, 0, 1}, 80});
  bars.push_back({{0.3, 0.3, 0.3}, {0, 1, 0}, 120});
  for (int i = 0; i < 4; ++i) {
    const Vec3 at{0.5 + 0.3 * i, 1.5, 0.2};
    bars.push_back({at, {1, 0, 0}, 100});
    bars.push_back({at + Vec3{1e-9, 0, 0}, {0, 1, 0}, 90});
  }
  const LayoutStage automatic(registry, bars, WorldDef{}), direct(registry, bars, method("direct"));
  for (const Vec3& f : automatic.forces()) ASSERT_TRUE(is_finite(f));
  EXPECT_NE(automatic.stage().used_method(), Summation::Tree) << "below the tree's crossover";
  EXPECT_LT(rms_relative(automatic.forces(), direct.forces()), 1e-3);
}

TEST_F(MagneticForcesMethod, AutoChecksEveryFewUpdatesOrWhenTheMagnetsMoveMuch) {
  // The check's schedule (kAutoCheckEvery): at the first update, then every
  // eighth while the magnets move little (1 mm a step against a quarter of
  // the bars' 85 mm), at once when more than 1 % of them move 3 cm, and every update
  // while it fails (the packed block). Between checks the forces are the
  // FMM's, within the tolerance of the direct sum at the same places.
  static_assert(kAutoCheckEvery == 8);
  const auto bars = layouts::random_bars(500, 3);
  LayoutStage automatic(registry, bars, WorldDef{});
  World& w = automatic.world;
  std::vector<ObjectId> ids;
  for (const MagneticBody& b : automatic.stage().bodies()) ids.push_back(b.id);
  auto shift = [&](std::size_t from, std::size_t to, Vec3 by) {
    for (std::size_t i = from; i < to; ++i)
      w.set(ids[i], prop::kPosition, *w.value<Vec3>(ids[i], prop::kPosition) + by);
  };
  std::vector<int> checked_at;
  EXPECT_TRUE(automatic.stage().checked());
  for (int update = 2; update <= 18; ++update) {
    shift(0, ids.size(), {0.001, 0, 0});
    const std::uint64_t before = automatic.stage().updates();
    w.step();
    ASSERT_EQ(automatic.stage().updates(), before + 1) << "the stage ran";
    EXPECT_EQ(automatic.stage().used_method(), Summation::Fmm);
    if (automatic.stage().checked()) checked_at.push_back(update);
  }
  EXPECT_EQ(checked_at, (std::vector<int>{9, 17}));
  // Unchecked forces are still within the tolerance of the direct sum.
  std::vector<layouts::Bar> moved = bars;
  for (layouts::Bar& b : moved) b.centre += Vec3{0.017, 0, 0};
  const LayoutStage direct(registry, moved, method("direct"));
  EXPECT_FALSE(automatic.stage().checked());
  EXPECT_LT(rms_relative(automatic.forces(), direct.forces()), 1e-3);
  // One magnet 3 cm away (1 part in 500): not a new configuration; six
  // more (7 in 500, above 1 %): checked at the next update.
  shift(7, 8, {0, 0.03, 0});
  w.step();
  EXPECT_FALSE(automatic.stage().checked());
  shift(100, 106, {0, 0.03, 0});
  w.step();
  EXPECT_TRUE(automatic.stage().checked());
  shift(0, ids.size(), {0.001, 0, 0});
  w.step();
  EXPECT_FALSE(automatic.stage().checked());
  // The packed block fails its check, so every update checks again.
  LayoutStage block(registry, layouts::packed_bars(10, 8, 8), WorldDef{});
  std::vector<ObjectId> block_ids;
  for (const MagneticBody& b : block.stage().bodies()) block_ids.push_back(b.id);
  for (int update = 2; update <= 4; ++update) {
    for (ObjectId id : block_ids)
      block.world.set(id, prop::kPosition,
                      *block.world.value<Vec3>(id, prop::kPosition) + Vec3{0.001, 0, 0});
    block.world.step();
    EXPECT_TRUE(block.stage().checked()) << update;
    EXPECT_EQ(block.stage().used_method(), Summation::Direct) << update;
  }
}

TEST(AutoCheck, SampledErrorFollowsTheFullError) {
  // The check's estimate on 32 of the parts against the RMS error over all of
  // them, for FMM forces on spread magnets (about 3e-4) and on a packed block
  // (several percent): within a factor of 3 each, so that 1e-3 tells them apart.
  for (bool packed : {false, true}) {
    const Bars bars = packed ? packed_bars(10, 8, 8) : random_bars(1000, 11);
    std::vector<Vec3> fast(bars.poles.size()), exact(bars.poles.size());
    accumulate_pole_forces(bars.poles, 0.005, fast, {.method = Summation::Fmm, .theta = kFmmTheta});
    accumulate_pole_forces(bars.poles, 0.005, exact, kDirect);
    std::vector<MagneticBody> bodies(bars.count());
    std::vector<Vec3> f(bars.count()), e(bars.count());
    for (std::uint32_t b = 0; b < bars.count(); ++b) {
      bodies[b].first_pole = 2 * b, bodies[b].pole_count = 2;
      f[b] = fast[2 * b] + fast[2 * b + 1], e[b] = exact[2 * b] + exact[2 * b + 1];
    }
    const double full = rms_relative(f, e);
    const double sampled = sampled_force_error(bars.poles, bodies, fast, 0.005);
    EXPECT_GT(sampled, full / 3) << packed;
    EXPECT_LT(sampled, full * 3) << packed;
    EXPECT_EQ(sampled_force_error(bars.poles, bodies, exact, 0.005) < 1e-12, true) << packed;
  }
}

}  // namespace
}  // namespace alloy::magnetism
