// gravity.nbody against Newton: two bodies, a circular orbit against Kepler,
// static sources, areas, skipping when nothing moves, settings.
#include "resolvers/gravity/nbody_gravity.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <numbers>
#include <random>
#include <string>

#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::scenes {
namespace {

constexpr double kPi = std::numbers::pi;

Vec3 gravity(Sim& s, ObjectId o) {
  return std::get<Vec3>(s->get(o, "gravity"));
}

WorldDef nbody_world(double G, double softening = 0) {
  WorldDef def;
  def.use = {{"gravity", "gravity.nbody"}};
  def.settings["gravity.nbody"].set("G", G);
  def.settings["gravity.nbody"].set("softening", softening);
  return def;
}

TEST(NBodyAccelerations, DirectSumWithoutSelfPullAndCoincidentPointsExertNothing) {
  const std::vector<Vec3> x = {{0, 0, 0}, {3, 4, 0}, {-1, 2, 5}, {0, 0, 0}};
  const std::vector<double> m = {2, 5, 1, 3};
  std::vector<Vec3> a(x.size());
  gravity::accelerations(x, x, m, 0.5, 0, a);
  Vec3 momentum_rate{};
  for (std::size_t i = 0; i < x.size(); ++i) momentum_rate += m[i] * a[i];
  EXPECT_NEAR(length(momentum_rate), 0, 1e-14);  // every pair equal and opposite
  // Points 0 and 3 coincide: each feels only bodies 1 and 2.
  const auto pull = [&](std::size_t i, std::size_t j) {
    const Vec3 d = x[j] - x[i];
    return (0.5 * m[j] / std::pow(dot(d, d), 1.5)) * d;
  };
  const Vec3 expect0 = pull(0, 1) + pull(0, 2);
  EXPECT_NEAR(a[0].x, expect0.x, 1e-15);
  EXPECT_NEAR(a[0].y, expect0.y, 1e-15);
  EXPECT_NEAR(a[0].z, expect0.z, 1e-15);
  EXPECT_EQ(a[0], a[3]);
  // Points that are not sources: the field of the sources there.
  std::vector<Vec3> probe(1);
  gravity::accelerations(std::vector<Vec3>{{0, 10, 0}}, std::vector<Vec3>{{0, 0, 0}},
                         std::vector<double>{4}, 2.0, 0, probe);
  EXPECT_EQ(probe[0], (Vec3{0, -2.0 * 4 / 100, 0}));
}

double rms_relative(const std::vector<Vec3>& approx, const std::vector<Vec3>& exact) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    num += dot(approx[i] - exact[i], approx[i] - exact[i]);
    den += dot(exact[i], exact[i]);
  }
  return std::sqrt(num / den);
}

/// Layouts for the summation's checks and studies: 0 the bench's grid (1 m
/// apart, 1,000 kg), 1 a Gaussian cluster (sigma n^(1/3) m, 1,000 kg), 2 a
/// uniform cube with masses from 1 to 100 kg, 3 a Plummer sphere (scale
/// n^(1/3) m, masses from 1 to 100 kg): a dense core in a sparse halo.
void layout(int kind, int n, std::uint64_t seed, std::vector<Vec3>& x, std::vector<double>& m) {
  std::mt19937_64 rng(seed);
  const double scale = std::cbrt(double(n));
  std::normal_distribution<double> g(0, scale);
  std::uniform_real_distribution<double> u(0, 1), um(1, 100);
  const int side = int(std::ceil(scale - 1e-9));
  x.resize(n), m.resize(n);
  for (int i = 0; i < n; ++i) {
    if (kind == 0) {
      x[i] = {1.0 * (i % side), 1.0 * (i / side % side), 1.0 * (i / (side * side))};
    } else if (kind == 1) {
      x[i] = {g(rng), g(rng), g(rng)};
    } else if (kind == 2) {
      x[i] = {scale * u(rng), scale * u(rng), scale * u(rng)};
    } else {
      // Plummer: r = a / sqrt(X^(-2/3) - 1), X uniform, capped at 20 a.
      const double X = 0.001 + 0.998 * u(rng);
      const double r = std::min(20.0, 1.0 / std::sqrt(std::pow(X, -2.0 / 3) - 1)) * scale;
      const double z = 2 * u(rng) - 1, phi = 2 * kPi * u(rng), rho = std::sqrt(1 - z * z);
      x[i] = {r * rho * std::cos(phi), r * rho * std::sin(phi), r * z};
    }
    m[i] = kind < 2 ? 1e3 : um(rng);
  }
}

/// Comma-separated numbers from the environment variable `name`, or `fallback`.
std::vector<double> env_list(const char* name, const char* fallback) {
  const char* env = std::getenv(name);
  const std::string list = env ? env : fallback;
  std::vector<double> out;
  for (std::size_t at = 0; at < list.size();) {
    const std::size_t comma = std::min(list.find(',', at), list.size());
    out.push_back(std::atof(list.substr(at, comma - at).c_str()));
    at = comma + 1;
  }
  return out;
}

/// A study (--gtest_also_run_disabled_tests): the FMM's RMS relative
/// acceleration error against the direct sum and its CPU time (the best of
/// ALLOY_NBODY_REPS, default 3) at every (order, theta, leaf) of a grid, on
/// the four layouts above, at the sizes in ALLOY_NBODY_SIZES (default
/// 1000,3000,10000); order 0 is the Barnes-Hut walk, -1 the direct sum. ALLOY_NBODY_ORDERS,
/// ALLOY_NBODY_THETAS and ALLOY_NBODY_LEAVES narrow the grid. One line per
/// setting and size: the time summed over the layouts, the worst error, and
/// each layout's. How kTreeTheta, kTreeOrder and kTreeLeaf were chosen
/// (docs/gravity.md, "Many bodies").
TEST(NBodyAccelerations, DISABLED_FmmSettingsSweep) {
  const auto sizes = env_list("ALLOY_NBODY_SIZES", "1000,3000,10000");
  const auto orders = env_list("ALLOY_NBODY_ORDERS", "0,1,2,3,4,5,6");
  const auto thetas = env_list("ALLOY_NBODY_THETAS", "0.4,0.45,0.5,0.55,0.6,0.65,0.7,0.75,0.8");
  const auto leaves = env_list("ALLOY_NBODY_LEAVES", "16,24,32,48,64");
  const int reps = int(env_list("ALLOY_NBODY_REPS", "3")[0]);
  auto cpu = [] { return double(std::clock()) / CLOCKS_PER_SEC; };
  for (double size : sizes) {
    const int n = int(size);
    std::vector<std::vector<Vec3>> xs(4), exact(4);
    std::vector<std::vector<double>> ms(4);
    for (int k = 0; k < 4; ++k) {
      layout(k, n, 11 + k, xs[k], ms[k]);
      exact[k].resize(n);
      gravity::accelerations(xs[k], xs[k], ms[k], 1.0, 0.0, exact[k]);
    }
    std::vector<Vec3> a(n);
    multipole::Tree tree;
    for (double order : orders)
      for (double theta : thetas)
        for (double leaf : leaves) {
          double worst = 0, time = 0;
          std::array<double, 4> err{}, ms_k{};
          for (int k = 0; k < 4; ++k) {
            double best = 1e30;
            for (int rep = 0; rep < reps; ++rep) {
              const double c0 = cpu();
              if (order < 0)
                gravity::accelerations(xs[k], xs[k], ms[k], 1.0, 0.0, a);
              else
                gravity::tree_accelerations(xs[k], ms[k], 1.0, 0.0, tree, a, theta, int(order),
                                            std::uint32_t(leaf));
              best = std::min(best, cpu() - c0);
            }
            time += best, ms_k[k] = 1e3 * best;
            err[k] = rms_relative(a, exact[k]);
            worst = std::max(worst, err[k]);
          }
          std::printf(
              "n %6d order %d theta %.2f leaf %2u: %8.3f ms (4 layouts), worst error %.2e (grid "
              "%.1e cluster %.1e cube %.1e plummer %.1e; ms %.2f %.2f %.2f %.2f)\n",
              n, int(order), theta, unsigned(leaf), 1e3 * time, worst, err[0], err[1], err[2],
              err[3], ms_k[0], ms_k[1], ms_k[2], ms_k[3]);
        }
  }
}

TEST(NBodyAccelerations, TheStagesSettingsKeepTheErrorBoundOnFourLayouts) {
  // Issue 16: the resolver's walk (below kFmmFromMasses) and FMM (from it)
  // at their settings, on the grid, the Gaussian cluster, the uniform cube
  // with uneven masses and the Plummer sphere, at both sides of the switch.
  for (int n : {int(gravity::kTreeFromMasses) + 36, int(gravity::kFmmFromMasses) - 1,
                int(gravity::kFmmFromMasses), 4000}) {
    for (int kind = 0; kind < 4; ++kind) {
      std::vector<Vec3> x;
      std::vector<double> m;
      layout(kind, n, 100 + kind, x, m);
      std::vector<Vec3> exact(n), approx(n);
      gravity::accelerations(x, x, m, 1.0, 0.0, exact);
      multipole::Tree tree;
      if (std::size_t(n) >= gravity::kFmmFromMasses)
        gravity::tree_accelerations(x, m, 1.0, 0.0, tree, approx);
      else
        gravity::tree_accelerations(x, m, 1.0, 0.0, tree, approx, gravity::kWalkTheta, 0,
                                    gravity::kWalkLeaf);
      const double e = rms_relative(approx, exact);
      EXPECT_LT(e, gravity::kErrorBound) << n << " bodies, layout " << kind;
      EXPECT_GT(e, 0) << n << " bodies, layout " << kind;  // summed, not exact
    }
  }
}

TEST(NBodyAccelerations, TreeAgreesWithTheDirectSumOnAGridAndAClusterAndCoincidentBodies) {
  // Issue 16: from kTreeFromMasses masses the resolver sums with the tree.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0, 3.0);
  std::uniform_real_distribution<double> u(1, 100);
  for (int layout = 0; layout < 2; ++layout) {
    std::vector<Vec3> x;
    std::vector<double> m;
    for (int i = 0; i < 1500; ++i) {
      x.push_back(layout == 0 ? Vec3{double(i % 12), double(i / 12 % 12), double(i / 144)}
                              : Vec3{g(rng), g(rng), g(rng)});
      m.push_back(u(rng));
    }
    x[7] = x[8];  // two bodies on one spot: they pull each other with nothing (eps = 0)
    std::vector<Vec3> exact(x.size()), approx(x.size());
    gravity::accelerations(x, x, m, 1.0, 0.0, exact);
    multipole::Tree tree;
    gravity::tree_accelerations(x, m, 1.0, 0.0, tree, approx);
    const double e = rms_relative(approx, exact);
    std::printf("%s of 1,500: RMS relative error %.2e\n", layout ? "cluster" : "grid", e);
    EXPECT_LT(e, 1e-3);
    for (const Vec3& a : approx) EXPECT_TRUE(is_finite(a));
  }
}

TEST(NBodyGravity, ManyBodiesUseTheTreeAndAgreeWithTheDirectSum) {
  const double G = 6.67430e-11;
  Sim s(nbody_world(G, 0.01));
  std::vector<ObjectId> ids;
  std::vector<Vec3> x;
  std::vector<double> m;
  const int n = int(gravity::kTreeFromMasses) + 100;
  for (int i = 0; i < n; ++i) {
    x.push_back({1.0 * (i % 9), 1.0 * (i / 9 % 9), 1.0 * (i / 81)});
    m.push_back(1000.0 + i);
    ids.push_back(add_sphere(*s, x.back(), 0.1, m.back()));
  }
  s->start();
  std::vector<Vec3> exact(x.size()), got;
  gravity::accelerations(x, x, m, G, 0.01, exact);
  for (ObjectId id : ids) got.push_back(gravity(s, id));
  const double e = rms_relative(got, exact);
  EXPECT_LT(e, 1e-3);
  EXPECT_GT(e, 0);  // the tree's, not the direct sum's (which would be exact)
}

TEST(NBodyGravity, TwoBodiesFeelNewtonsForceEqualAndOpposite) {
  const double G = 6.67430e-11, r = 2.0;
  for (double eps : {0.0, 0.05}) {
    Sim s(nbody_world(G, eps));
    const ObjectId a = add_sphere(*s, {0, 0, 0}, 0.1, 1000, "a");
    const ObjectId b = add_sphere(*s, {r, 0, 0}, 0.1, 250, "b");
    s->start();
    ASSERT_TRUE(s->has_stage("gravity.nbody"));
    EXPECT_FALSE(s->has_stage("gravity.uniform"));  // one provider of gravity
    const Vec3 fa = 1000.0 * gravity(s, a), fb = 250.0 * gravity(s, b);
    const double newton = G * 1000 * 250 / (r * r);
    const double softened = G * 1000 * 250 * r / std::pow(r * r + eps * eps, 1.5);
    EXPECT_NEAR(fa.x, softened, 1e-12 * newton) << "eps " << eps;
    EXPECT_EQ(fa.y, 0);
    EXPECT_NEAR(fa.x + fb.x, 0, 1e-15 * newton);  // third law
    // The softening error is (1 + eps^2/r^2)^(-3/2) - 1, about 1.5 eps^2 / r^2.
    EXPECT_LE(std::abs(fa.x - newton), 1.5 * eps * eps / (r * r) * newton + 1e-12 * newton);
  }
}

TEST(NBodyGravity, AStaticMassPullsAndFeelsNothing) {
  Sim s(nbody_world(1.0));
  const ObjectId sun = add_sphere(*s, {0, 0, 0}, 1, 100, "sun");
  s->set(sun, "static", true);
  const ObjectId rock = add_sphere(*s, {0, 10, 0}, 0.1, 1, "rock");
  s->start();
  EXPECT_THROW(s->get(sun, "gravity"), AccessError);
  const Vec3 g = gravity(s, rock);
  EXPECT_NEAR(g.y, -1.0 * 100 / (10 * 10), 1e-12);  // G M / r^2
  EXPECT_EQ(g.x, 0);
  // The rock moves toward the sun; the sun stays.
  s->run(10);
  EXPECT_EQ(s.position(sun), (Vec3{0, 0, 0}));
  EXPECT_LT(s.position(rock).y, 10);
}

TEST(NBodyGravity, InAnAreaEveryMassPullsUnlessSourcesAreTheAreas) {
  // A sun outside the area, a rock inside it: the area's N-body stage
  // computes the rock's gravity, from the sun too unless sources = "area".
  for (const char* sources : {"world", "area"}) {
    WorldDef def;
    AreaDef box{.name = "box",
                .center = {0, 10, 0},
                .half_extents = {1, 1, 1},
                .plugins = {"gravity.nbody"}};
    box.settings["gravity.nbody"].set("G", 1.0);
    box.settings["gravity.nbody"].set("sources", std::string(sources));
    def.areas.push_back(box);
    Sim s(def);
    const ObjectId sun = add_sphere(*s, {0, 0, 0}, 1, 100, "sun");
    s->set(sun, "static", true);
    const ObjectId rock = add_sphere(*s, {0, 10, 0}, 0.1, 1, "rock");
    const ObjectId pebble = add_sphere(*s, {0, 10.5, 0}, 0.05, 0.5, "pebble");
    s->start();
    ASSERT_TRUE(s->has_stage("gravity.nbody@box"));
    const double from_pebble = 0.5 / (0.5 * 0.5);
    const double expect = std::string(sources) == "world" ? from_pebble - 100.0 / 100 : from_pebble;
    EXPECT_NEAR(gravity(s, rock).y, expect, 1e-12) << sources;
    EXPECT_EQ(s->area_of(pebble), "box");
  }
}

TEST(NBodyGravity, ComputesNothingWhileNothingMoves) {
  Sim s(nbody_world(1.0));
  const ObjectId a = add_sphere(*s, {0, 0, 0}, 0.1, 1, "a");
  const ObjectId b = add_sphere(*s, {1, 0, 0}, 0.1, 1, "b");
  s->set(a, "pinned", true);
  s->set(b, "pinned", true);
  s->step();
  const auto& nbody = dynamic_cast<gravity::NBodyGravity&>(*s->stage("gravity.nbody"));
  const std::uint64_t n = nbody.evaluations();
  const auto& column = s->store().column(s->properties().id("gravity"));
  const std::uint64_t v = column.version();
  s->run(50);
  EXPECT_EQ(nbody.evaluations(), n);
  EXPECT_EQ(column.version(), v);
  s->set(b, "pinned", false);  // b falls toward a: recomputed every step
  s->run(5);
  EXPECT_EQ(nbody.evaluations(), n + 5);
  EXPECT_LT(s.velocity(b).x, 0);
}

/// Two free bodies on a circular orbit about their centre of mass, in the
/// xy plane. Returns the measured period (mean over `orbits` orbits) from the
/// unwrapped angle of the separation, interpolated between steps.
double measured_period(double dt, int orbits, double* kepler, double* radius_error) {
  const double G = 1.0, m1 = 3.0, m2 = 1.0, d = 2.0, M = m1 + m2;
  WorldDef def = nbody_world(G);
  def.dt = dt;
  Sim s(def);
  // Relative speed sqrt(G M / d), shared so that the momentum is zero.
  const double vrel = std::sqrt(G * M / d);
  const ObjectId a = add_sphere(*s, {-d * m2 / M, 0, 0}, 0.05, m1, "a");
  const ObjectId b = add_sphere(*s, {d * m1 / M, 0, 0}, 0.05, m2, "b");
  s->set(a, "velocity", Vec3{0, -vrel * m2 / M, 0});
  s->set(b, "velocity", Vec3{0, vrel * m1 / M, 0});
  *kepler = 2 * kPi * std::sqrt(d * d * d / (G * M));
  double angle = 0, last = 0, crossing_time = 0;
  *radius_error = 0;
  while (true) {
    s->step();
    const Vec3 r = s.position(b) - s.position(a);
    *radius_error = std::max(*radius_error, std::abs(length(r) - d) / d);
    double now = std::atan2(r.y, r.x);
    double delta = now - last;
    if (delta < -kPi) delta += 2 * kPi;
    last = now;
    const double before = angle;
    angle += delta;
    if (angle >= 2 * kPi * orbits) {
      const double f = (2 * kPi * orbits - before) / (angle - before);
      crossing_time = s->time() - dt + f * dt;
      break;
    }
  }
  return crossing_time / orbits;
}

TEST(NBodyGravity, CircularTwoBodyOrbitKeepsKeplersPeriod) {
  // Semi-implicit Euler is first order, but its error in the period of a
  // closed orbit is second order: the first-order term of its modified energy
  // averages to zero over an orbit. Its first-order error shows instead as the
  // half-step offset between position and velocity, an eccentricity of about
  // omega dt / 2 in an orbit started exactly circular.
  double errors[2];
  int i = 0;
  for (double dt : {1.0 / 240, 1.0 / 960}) {
    double kepler = 0, radius_error = 0;
    const double period = measured_period(dt, 5, &kepler, &radius_error);
    const double error = std::abs(period - kepler) / kepler;
    const double omega_dt = 2 * kPi / kepler * dt;
    std::printf(
        "dt 1/%.0f: period %.6f s, Kepler %.6f s, error %.2e; radius within %.2e (omega dt %.2e)\n",
        1 / dt, period, kepler, error, radius_error, omega_dt);
    EXPECT_LT(error, 2e-5) << "dt 1/" << 1 / dt;
    EXPECT_LT(radius_error, omega_dt) << "dt 1/" << 1 / dt;
    errors[i++] = error;
  }
  EXPECT_GT(errors[0] / errors[1], 8.0);  // 4x smaller dt, about 16x smaller error
}

TEST(NBodyGravity, SettingsAreChecked) {
  for (auto [key, value] :
       {std::pair{"G", -1.0}, std::pair{"softening", -0.1}, std::pair{"g", 1.0}}) {
    WorldDef def;
    def.use = {{"gravity", "gravity.nbody"}};
    def.settings["gravity.nbody"].set(key, value);
    Sim s(def);
    add_sphere(*s, {0, 1, 0}, 0.1, 1.0);
    EXPECT_THROW(s->start(), InputError) << key;
  }
}

/// A study, not a check (run with --gtest_also_run_disabled_tests; under
/// `perf record -g` for the profile): the bench's nbody scene (bench/scaling.cpp,
/// n spheres of 1,000 kg on a grid 1 m apart; n from ALLOY_NBODY_N, default
/// 10,000) stepped 3 times to warm up and 20 times timed (ALLOY_NBODY_STEPS); prints every stage's
/// wall time per step and the loop's CPU / wall ratio.
TEST(NBodyGravity, DISABLED_StageProfile) {
  const char* env = std::getenv("ALLOY_NBODY_N");
  const int n = env ? std::atoi(env) : 10000;
  Sim s(nbody_world(gravity::kGravitationalConstant));
  const int side = int(std::ceil(std::cbrt(double(n)) - 1e-9));
  for (int i = 0; i < n; ++i)
    add_sphere(*s, {1.0 * (i % side), 1.0 * (i / side % side), 1.0 * (i / (side * side))}, 0.05,
               1e3);
  s->set_timing(true);
  s->start();
  s->run(3);
  std::vector<double> before;
  for (const StageTiming& t : s->profile().stages) before.push_back(t.seconds);
  const char* env_steps = std::getenv("ALLOY_NBODY_STEPS");
  const int steps = env_steps ? std::atoi(env_steps) : 20;
  const std::clock_t c0 = std::clock();
  const double w0 = now_seconds();
  s->run(steps);
  const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC, wall = now_seconds() - w0;
  std::printf("%d bodies, %d steps: CPU %.2f ms a step, wall %.2f ms (CPU / wall %.2f)\n", n, steps,
              1e3 * cpu / steps, 1e3 * wall / steps, cpu / wall);
  const auto& stages = s->profile().stages;
  // A stage's CPU time is estimated as its wall time scaled by the loop's
  // CPU / wall ratio (as bench/scaling.cpp does on a shared machine).
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const double ms = 1e3 * (stages[i].seconds - (i < before.size() ? before[i] : 0)) / steps;
    std::printf("  %-28s %8.3f ms a step (wall), %8.3f scaled to CPU\n", stages[i].name.c_str(), ms,
                ms * cpu / wall);
  }
}

}  // namespace
}  // namespace alloy::scenes
