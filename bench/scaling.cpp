// Scaling (issue 6, item 4): time per step against the number of objects n,
// for each resolver, derived set and interaction that can be isolated, with
// the growth exponent fitted over the upper half of n; and the magnetic forces
// summed directly and with the Barnes-Hut tree: both times, the crossover n
// and the tree's error against the direct sum at every n.
//
//   build/bench/alloy_bench_scaling [--quick] [--out DIR] [--docs FILE] [--no-progress]
//                                   [--electricity] [--collisions] [--magnets] [--gravity]
//                                   [--ladder]
//
// n runs to 100,000; above 10,000 each point is sampled sparingly (a few
// steps, skipped if predicted slower than 2 s a step), so that the sweep fits
// `make bench`. The goals of issue 16 are printed as pass or miss at the end
// (exit code 1 on a miss, as bench/run_all.sh expects).
//
// --electricity / --collisions / --magnets / --gravity run only those rows
// (and their goals), print the table and write nothing: for working on one
// stage without the hour of the whole sweep. --magnets and --gravity also
// print issue 16's kernel comparison (previous method against current, same
// run, same machine) with the goals as pass or miss. --ladder times the
// 10,000-element ladder alone at the default settings and with 1 substep
// (400 steps each; seconds, not the hour): what to profile the goal with.
//
// Scenes (each built through the world's editing API, only the plugins it
// needs allowed, so that a stage's time is its own):
//   free      n boxes in a 3D grid 0.5 m apart, falling (no contact anywhere):
//             rigid_body, collisions (broad phase finds nothing), gravity.uniform,
//             rigid_body_from_gravity
//   resting   n boxes resting on a floor, 0.3 m apart: 4 contacts each
//   nbody     n spheres 1 m apart under gravity.nbody (every pair)
//   magnets   n kit bars (10 cm, 50-150 A*m) at random places and directions in
//             a cube of one bar per (0.15 m)^3, free to move (no gravity, no
//             collisions): magnetism, magnetic_forces (auto, the default; then tree, direct, on the
//             same world), rigid_body_from_magnetism
//   ladder    a battery feeding a ladder of n/2 series resistors and n/2 coil
//             rungs, wired: electricity with dense LU, and with the sparse
//             L D L^T of the reduced Laplacian (resolvers/electricity/mna.hpp)
//   mesh      n resistors and coils (one in four a coil) joining random
//             neighbouring junctions of a square grid of n/2 junctions, fed by
//             one battery: a random planar mesh with many loops (sparse LU)
//   voices    n parts ringing at once (struck once, T60 30 s): sound
//   mixed     n/3 resting boxes, a ladder of n/3 circuit elements and n/3 kit
//             magnets falling together: the whole step (CPU of World::step())
//
// Timing: each stage's time is World::profile()'s (wall clock) over the timed
// steps, scaled by the loop's CPU / wall ratio, so a busy machine does not
// inflate it. Each point runs warm-up steps, then timed steps until 0.3 s of
// CPU (quick: 0.03 s) or 200 steps, at least one. A point whose predicted time
// per step (from the last two points' growth) exceeds 20 s is skipped and the
// table says so.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "bench/common/bench_common.hpp"
#include "resolvers/common/direct_kernel.hpp"
#include "resolvers/common/multipole_tree.hpp"
#include "resolvers/electricity/electricity.hpp"
#include "resolvers/gravity/nbody_gravity.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "resolvers/magnetism/pole_model.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/sound/sound_resolver.hpp"
#include "tests/resolvers/magnetism/magnet_layouts.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace {

using namespace alloy;
using namespace alloy::bench;

constexpr double kSkipSeconds = 20;  // a point predicted slower than this per step is skipped
// Above kLargeN objects a point is sampled sparingly (the sweep to 100,000
// must fit `make bench`'s budget): at most kLargeWarmup warm-up steps, at
// most kLargeSteps timed ones, and skipped when predicted slower than
// kLargeSkipSeconds a step.
constexpr int kLargeN = 10000;
constexpr int kLargeWarmup = 3;
constexpr int kLargeSteps = 3;
constexpr double kLargeSkipSeconds = 2;

// --- scenes --------------------------------------------------------------------------

WorldDef def_with(std::vector<std::string> plugins) {
  WorldDef d;
  d.plugins = std::move(plugins);
  return d;
}

int cube_side(int n) {
  return std::max(1, int(std::ceil(std::cbrt(double(n)) - 1e-9)));
}

void build_free(World& w, int n) {
  const int s = cube_side(n);
  for (int i = 0; i < n; ++i)
    scenes::add_box(w, {0.5 * (i % s), 0.5 * (i / s % s) + 100, 0.5 * (i / (s * s))},
                    {0.2, 0.2, 0.2}, 1.0);
}

void build_resting(World& w, int n) {
  const int s = std::max(1, int(std::ceil(std::sqrt(double(n)))));
  scenes::add_floor(w, 0, {0.3 * s + 2, 1, 0.3 * s + 2});
  for (int i = 0; i < n; ++i)
    scenes::add_box(w, {0.3 * (i % s - s / 2), 0.1, 0.3 * (i / s - s / 2)}, {0.2, 0.2, 0.2}, 1.0);
}

void build_nbody(World& w, int n) {
  const int s = cube_side(n);
  for (int i = 0; i < n; ++i)
    scenes::add_sphere(w, {1.0 * (i % s), 1.0 * (i / s % s), 1.0 * (i / (s * s))}, 0.05, 1e3);
}

/// The tests' random magnets (tests/resolvers/magnetism/magnet_layouts.hpp), as bodies.
void build_magnets(World& w, int n) {
  for (const layouts::Bar& bar : layouts::random_bars(std::size_t(n), 1)) {
    const Vec3 c = bar.centre, a = bar.axis;
    const double q = bar.strength;
    // The rotation taking x to the random direction a: about x cross a.
    Vec3 axis = cross({1, 0, 0}, a);
    const double sin_angle = length(axis);
    const Quat rot = sin_angle > 1e-12
                         ? Quat::from_axis_angle(axis / sin_angle, std::atan2(sin_angle, a.x))
                         : Quat{};
    const ObjectId id = scenes::add_box(w, c, {0.1, 0.02, 0.02}, 0.15, rot);
    w.set(id, "magnet", std::string("permanent"));
    w.set(id, "pole_strength", q);
  }
}

ObjectId part(World& w, const std::string& name, const char* kind, double value) {
  const ObjectId id = w.create(name);
  w.set(id, "conductive", true);
  if (std::string(kind) == "emf") {
    w.set(id, "emf", value);
    w.set(id, "internal_resistance", 0.1);
  } else if (std::string(kind) == "coil") {
    w.set(id, "inductance", value);
    w.set(id, "resistance", 5.0);
  } else {
    w.set(id, "resistance", value);
  }
  return id;
}

void wire(World& w, ObjectId a, int ta, ObjectId b, int tb) {
  const ObjectId id = w.create();
  w.set(id, "wire_from", a);
  w.set(id, "wire_from_terminal", std::int64_t(ta));
  w.set(id, "wire_to", b);
  w.set(id, "wire_to_terminal", std::int64_t(tb));
  w.set(id, "resistance", 0.01);
}

/// A battery feeding a ladder: n/2 series resistors along the top rail, and
/// from each rail node a coil rung down to the ground bar. n elements in all.
void build_ladder(World& w, int n) {
  const ObjectId battery = part(w, "battery", "emf", 6.0);
  const ObjectId ground = w.create("ground");
  w.set(ground, "conductive", true);
  wire(w, battery, 0, ground, 0);
  ObjectId rail = battery;
  int rail_terminal = 1;
  for (int i = 0; i < std::max(1, n / 2); ++i) {
    const ObjectId r = part(w, "r" + std::to_string(i), "resistor", 1.0);
    const ObjectId l = part(w, "l" + std::to_string(i), "coil", 0.05);
    wire(w, rail, rail_terminal, r, 0);
    wire(w, r, 1, l, 0);
    wire(w, l, 1, ground, 0);
    rail = r;
    rail_terminal = 1;
  }
}

/// The ladder with resistors (10 Ohm) for rungs instead of coils: a purely
/// resistive circuit, whose sources are the same at every substep.
void build_resistive_ladder(World& w, int n) {
  const ObjectId battery = part(w, "battery", "emf", 6.0);
  const ObjectId ground = w.create("ground");
  w.set(ground, "conductive", true);
  wire(w, battery, 0, ground, 0);
  ObjectId rail = battery;
  for (int i = 0; i < std::max(1, n / 2); ++i) {
    const ObjectId r = part(w, "r" + std::to_string(i), "resistor", 1.0);
    const ObjectId rung = part(w, "g" + std::to_string(i), "resistor", 10.0);
    wire(w, rail, 1, r, 0);
    wire(w, r, 1, rung, 0);
    wire(w, rung, 1, ground, 0);
    rail = r;
  }
}

/// A random mesh: junctions on a square grid (n/2 of them), each of the n
/// elements (a coil one time in four, else a resistor) joining a random
/// junction to a random one of its grid neighbours, plus a battery across
/// two corners. Fixed seed: the same mesh every run.
void build_mesh(World& w, int n) {
  std::mt19937_64 rng(7);
  const int side = std::max(2, int(std::ceil(std::sqrt(std::max(1, n / 2)))));
  std::vector<ObjectId> junction(std::size_t(side) * side);
  for (std::size_t j = 0; j < junction.size(); ++j) {
    junction[j] = w.create();
    w.set(junction[j], "conductive", true);
  }
  std::uniform_int_distribution<int> pick(0, side * side - 1), dir(0, 3);
  for (int i = 0; i < n; ++i) {
    const int a = pick(rng), d = dir(rng);
    int x = a % side + (d == 0) - (d == 1), y = a / side + (d == 2) - (d == 3);
    x = std::clamp(x, 0, side - 1), y = std::clamp(y, 0, side - 1);
    const int b = y * side + x == a ? (a + 1) % (side * side) : y * side + x;
    const bool coil = i % 4 == 0;
    const ObjectId e = part(w, (coil ? "l" : "r") + std::to_string(i), coil ? "coil" : "resistor",
                            coil ? 0.05 : 1.0 + (i % 7));
    wire(w, junction[a], 0, e, 0);
    wire(w, e, 1, junction[b], 0);
  }
  const ObjectId battery = part(w, "battery", "emf", 6.0);
  wire(w, battery, 0, junction.front(), 0);
  wire(w, battery, 1, junction.back(), 0);
}

/// A third of each: boxes resting on a floor (as `resting`), a ladder of
/// circuit elements (as `ladder`), and kit bar magnets (100 A*m, on a grid
/// 0.3 m apart, alternating in direction, 50 m above the floor, falling).
void build_mixed(World& w, int n) {
  build_resting(w, std::max(1, n / 3));
  build_ladder(w, std::max(2, n / 3));
  const int m = std::max(1, n - 2 * (n / 3)), s = cube_side(m);
  for (int i = 0; i < m; ++i) {
    const Vec3 at{0.3 * (i % s), 50 + 0.3 * (i / s % s), 0.3 * (i / (s * s))};
    const ObjectId id = scenes::add_box(w, at, {0.1, 0.02, 0.02}, 0.15,
                                        i % 2 ? Quat::from_angle_z(std::numbers::pi) : Quat{});
    w.set(id, "magnet", std::string("permanent"));
    w.set(id, "pole_strength", 100.0);
  }
}

void build_voices(World& w, int n) {
  for (int i = 0; i < n; ++i) {
    const ObjectId id = w.create();
    w.set(id, "acoustic", std::string("bar"));
    w.set(id, "pitch", 200.0 + i % 1000);
    w.set(id, "decay", 30.0);
  }
}

/// After start(): strike every ringing part once, so that n voices ring.
void strike_all(World& w) {
  auto& s = dynamic_cast<sound::SoundResolver&>(*w.stage("sound"));
  const PropertyStore& store = w.store();
  for (std::uint32_t slot = 0; slot < store.slot_count(); ++slot) {
    const ObjectId id = store.id_at(slot);
    if (store.alive(id)) s.strike({.part = id, .normal_speed = 2.0});
  }
}

// --- measuring ---------------------------------------------------------------------------

/// One stage of one scene, as a line of the plot and a row of the table.
struct Line {
  std::string label;     // "rigid_body (no contacts)"
  std::string stage;     // profile name
  std::string expected;  // "linear", "n log n", "quadratic", "cubic"
  std::vector<double> n, seconds;
  std::vector<std::string> skipped;  // "n = 3000: predicted 45 s per step"
};

struct Scene {
  std::string name;
  WorldDef def;
  std::function<void(World&, int)> build;
  std::vector<std::size_t> lines;  // indices into the lines
  int warmup = 2;
  std::function<void(World&)> after_start;
  int max_n = 1 << 30;
};

/// Per-stage seconds so far, by stage name.
std::map<std::string, double> stage_seconds(const World& w) {
  std::map<std::string, double> m;
  for (const StageTiming& t : w.profile().stages) m[t.name] += t.seconds;
  return m;
}

/// The pseudo-stage of a line that times the whole World::step().
constexpr const char* kWholeStep = "(whole step)";

struct Timed {
  std::map<std::string, double> per_step;  // CPU seconds per step, by stage
  int steps = 0;
};

/// Steps `w` until `budget` CPU seconds have passed (at least once, at most
/// max_steps) and returns each stage's time per step.
Timed time_steps(World& w, double budget, int max_steps) {
  w.set_timing(true);
  const auto before = stage_seconds(w);
  const double c0 = cpu_seconds(), w0 = now_seconds();
  int steps = 0;
  do {
    w.step();
    ++steps;
  } while (steps < max_steps && cpu_seconds() - c0 < budget);
  const double cpu = cpu_seconds() - c0, wall = now_seconds() - w0;
  const double scale = wall > 0 ? std::min(1.0, cpu / wall) : 1.0;
  Timed t;
  t.steps = steps;
  for (const auto& [name, s] : stage_seconds(w)) {
    const auto it = before.find(name);
    t.per_step[name] = (s - (it == before.end() ? 0.0 : it->second)) * scale / steps;
  }
  t.per_step[kWholeStep] = cpu / steps;  // every stage and the world's own work
  return t;
}

/// Predicted seconds per step at n from the line's last two points (growth at
/// least linear), or 0 if unknown.
double predict(const Line& l, double n) {
  const std::size_t k = l.n.size();
  if (k == 0) return 0;
  double slope = 1;
  if (k >= 2 && l.seconds[k - 1] > 0 && l.seconds[k - 2] > 0)
    slope = std::max(
        1.0, std::log(l.seconds[k - 1] / l.seconds[k - 2]) / std::log(l.n[k - 1] / l.n[k - 2]));
  return l.seconds[k - 1] * std::pow(n / l.n[k - 1], slope);
}

std::string growth_class(double slope) {
  if (!std::isfinite(slope)) return "-";
  if (slope < 0.5) return "flat (fixed cost)";
  if (slope < 1.25) return "linear";
  if (slope < 1.6) return "n log n .. n^1.5";
  if (slope < 2.5) return "quadratic";
  return "cubic";
}

/// Why each line grows as it does (the table's growth notes), by label.
std::string growth_reason(const std::string& label) {
  static const std::map<std::string, std::string> reasons = {
      {"rigid_body (no contacts)", "each body integrated once; no constraint rows"},
      {"collisions (no contacts)",
       "alloy's uniform grid, rebuilt each update: O(1) cells per part, a counting sort of the "
       "cell entries, no pair found"},
      {"gravity.uniform",
       "the resolver publishes one field; the per-body work is the interaction's"},
      {"rigid_body_from_gravity", "one force command per body"},
      {"rigid_body (contacts)",
       "ODE's quickstep: a fixed number of iterations over 4 contact rows per box"},
      {"collisions (contacts)",
       "the grid, the narrow phase once per touching pair (about 1 per box), a counting sort of "
       "the pairs and a linear merge with the last update's"},
      {"rigid_body_from_collisions", "one contact command per pair"},
      {"gravity.nbody",
       "the fast multipole method from 2,000 masses (O(n): a bounded number of cell pairs and "
       "near sources per body); the Barnes-Hut walk (n log n) below"},
      {"electricity (dense LU)",
       "dense back-substitution, 4 solves a step (factorisation cubic, once)"},
      {"electricity (sparse LDL^T)",
       "AMD keeps L of a ladder at O(n) entries; 4 solves a step of O(nnz(L)), O(n) output loops"},
      {"electricity (ladder, 1 substep)",
       "as the ladder with 1 solve a step instead of 4: O(nnz(L)) and O(n) loops"},
      {"electricity (resistive ladder)",
       "1 solve a step: the other substeps' sources are the same bits, the answer is reused; "
       "O(n) loops"},
      {"electricity (random mesh)",
       "fill of L on a planar mesh is O(n log n) at best (nested dissection); AMD comes near"},
      {"sound (n voices)", "each ringing voice synthesised every step"},
      {"magnetism", "a loop over coils"},
      {"magnetic_forces (auto)",
       "the default: the direct sum below 400 magnets, the FMM from there (O(n)) and its check "
       "on 32 magnets (O(n)); the tree where the check finds the FMM's error above the bound"},
      {"magnetic_forces (tree)", "Barnes-Hut: O(log n) cells per pole"},
      {"magnetic_forces (direct)", "every pair of poles"},
      {"rigid_body_from_magnetism", "one force and torque per magnet"},
      {"whole step, mixed scene", "the sum of the stages above; the slowest class dominates"},
  };
  const auto it = reasons.find(label);
  return it == reasons.end() ? "" : it->second;
}

/// Slope of log t against log n over the upper half of the measured n.
double upper_slope(const Line& l) {
  std::vector<double> x, y;
  const std::size_t from = l.n.size() / 2;
  for (std::size_t i = from; i < l.n.size(); ++i) {
    x.push_back(l.n[i]);
    y.push_back(l.seconds[i]);
  }
  if (x.size() < 2) return NAN;
  return loglog_slope(x, y);
}

// --- the magnetic forces: direct against tree ------------------------------------------

struct MagneticPoint {
  double n = 0, direct = 0, tree = 0, error = NAN, torque_error = NAN;
  bool direct_skipped = false;
  /// The stage as a user runs it (method "auto", the default): s per step,
  /// the method it took, the error its check measured, and its error
  /// against the direct sum (forces, torques).
  double automatic = NAN, auto_error = NAN, auto_torque_error = NAN, check_error = NAN;
  std::string auto_method = "-";
  /// At the same poles: the FMM's summation alone and auto's check alone, s.
  double sum_alone = NAN, check = NAN;
  /// The stage as session 18 left it (every translation at the full order,
  /// the check every update), same world, same run: s per step.
  double previous_auto = NAN;
  /// The share of the timed updates that ran the check.
  double checked_share = NAN;
};

double rms_relative(const std::vector<Vec3>& approx, const std::vector<Vec3>& exact) {
  double num = 0, den = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    const Vec3 e = approx[i] - exact[i];
    num += dot(e, e);
    den += dot(exact[i], exact[i]);
  }
  return std::sqrt(num / den);
}

/// The error of the tree on a packed block of aligned bars (the hard case:
/// near forces cancel), measured on the pole model alone.
double packed_error(int nx, int ny, int nz, double theta) {
  using namespace alloy::magnetism;
  std::vector<Pole> poles;
  std::uint32_t b = 0;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k, ++b) {
        const BarPoles p = bar_poles({0.1 * i, 0.02 * j, 0.02 * k}, {1, 0, 0}, 0.085);
        poles.push_back({p.north, 100, b});
        poles.push_back({p.south, -100, b});
      }
  auto forces = [&](SummationOptions o) {
    std::vector<Vec3> pf(poles.size());
    accumulate_pole_forces(poles, 0.005, pf, o);
    std::vector<Vec3> f(b);
    for (std::uint32_t i = 0; i < b; ++i) f[i] = pf[2 * i] + pf[2 * i + 1];
    return f;
  };
  return rms_relative(forces({.method = Summation::Tree, .theta = theta}),
                      forces({.method = Summation::Direct}));
}

// --- the circuits: the previous sparse method against the current one -------------------

struct SolverPoint {
  std::string scene;
  int n = 0;
  std::size_t unknowns = 0;
  // ms: first factor() (analysis + numeric), factor() of the same topology
  // with new impedances, one solve.
  double factor[2] = {}, refactor[2] = {}, solve[2] = {};
  double max_difference = 0;  // largest |potential| difference between the methods, V
};

/// The network the electricity resolver built for the scene, factorised and
/// solved by the supernodal LU (index 0, before issue 16) and by the reduced
/// L D L^T (index 1), all sparse.
SolverPoint compare_solvers(const std::string& scene, void (*build)(World&, int), int n,
                            double budget) {
  WorldDef d = def_with({"electricity"});
  d.settings["electricity"].set("dense_limit", std::int64_t(0));
  scenes::Sim sim(d);
  World& w = *sim;
  build(w, n);
  w.start();
  w.run(1);
  const electricity::Network net =
      dynamic_cast<electricity::ElectricityResolver&>(*w.stage("electricity")).network();
  electricity::Network changed = net;  // same topology, every impedance 10 % higher
  for (auto& b : changed.branches) b.z *= 1.1;
  SolverPoint p{.scene = scene, .n = n};
  std::vector<double> e(net.branches.size(), 0.0);
  for (std::size_t k = 0; k < e.size(); ++k) e[k] = 1.0 + 0.001 * double(k % 17);
  std::vector<double> potential[2], current(net.branches.size());
  const electricity::SparseMethod methods[2] = {electricity::SparseMethod::Lu,
                                                electricity::SparseMethod::Cholesky};
  for (int m = 0; m < 2; ++m) {
    electricity::MnaSolver s(0, methods[m]);
    p.factor[m] = 1e3 * cpu_time([&] { s.factor(net); });
    int reps = 0;
    const double c0 = cpu_seconds();
    do {
      s.factor(reps % 2 ? net : changed);
      ++reps;
    } while (cpu_seconds() - c0 < budget / 4 && reps < 50);
    p.refactor[m] = 1e3 * (cpu_seconds() - c0) / reps;
    if (reps % 2) s.factor(net);
    potential[m].assign(net.node_count, 0.0);
    reps = 0;
    const double c1 = cpu_seconds();
    do {
      s.solve(e, potential[m], current);
      ++reps;
    } while (cpu_seconds() - c1 < budget / 4 && reps < 1000);
    p.solve[m] = 1e3 * (cpu_seconds() - c1) / reps;
    for (std::size_t c = 0; c < s.component_count(); ++c) p.unknowns += m ? 0 : s.unknowns(c);
  }
  for (std::size_t v = 0; v < net.node_count; ++v)
    p.max_difference = std::max(p.max_difference, std::abs(potential[0][v] - potential[1][v]));
  return p;
}

/// The error of fewer substeps on the ladder: its n/2 coil currents after
/// `steps` steps with `substeps` a step, and the largest difference from a
/// reference run with `reference` substeps, relative to the largest current.
double ladder_substep_error(int n, int steps, int substeps, int reference) {
  auto currents = [&](int s) {
    WorldDef d = def_with({"electricity"});
    d.settings["electricity"].set("dense_limit", std::int64_t(0));
    d.settings["electricity"].set("substeps", std::int64_t(s));
    scenes::Sim sim(d);
    World& w = *sim;
    build_ladder(w, n);
    w.start();
    w.run(steps);
    std::vector<double> out;
    for (int i = 0; i < std::max(1, n / 2); ++i)
      out.push_back(std::get<double>(w.get(w.find("l" + std::to_string(i)), "current")));
    return out;
  };
  const std::vector<double> ref = currents(reference), got = currents(substeps);
  double largest = 0, worst = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    largest = std::max(largest, std::abs(ref[i]));
    worst = std::max(worst, std::abs(got[i] - ref[i]));
  }
  return worst / largest;
}

// --- issue 16, parts 1 and 2: magnetic forces and gravity.nbody, previous against current ---
// On the summation alone (no world): the previous methods (the per-magnet tree
// walk at theta 0.25 with leaves of 8; the scalar pair loop; gravity's direct
// sum) against the current ones (the blocked tree with SIMD near field at the
// default tolerance; the SIMD direct kernel; gravity on the tree), timed in
// CPU seconds in one run, with the error against the direct sum at every n.

/// CPU seconds per call of f: repeated until `budget` of CPU, at least once.
template <class F>
double cpu_per_call(F&& f, double budget) {
  const double c0 = cpu_seconds();
  int reps = 0;
  do {
    f();
    ++reps;
  } while (cpu_seconds() - c0 < budget && reps < 1000);
  return (cpu_seconds() - c0) / reps;
}

/// The tests' layouts (tests/resolvers/magnetism/magnet_layouts.hpp) as poles.
std::vector<magnetism::Pole> as_poles(const std::vector<layouts::Bar>& bars) {
  std::vector<magnetism::Pole> poles;
  std::uint32_t b = 0;
  for (const layouts::Bar& bar : bars) {
    const auto p = magnetism::bar_poles(bar.centre, bar.axis, layouts::kBarSeparation);
    poles.push_back({p.north, bar.strength, b});
    poles.push_back({p.south, -bar.strength, b++});
  }
  return poles;
}
std::vector<magnetism::Pole> random_poles(int n, std::uint64_t seed) {
  return as_poles(layouts::random_bars(std::size_t(n), seed));
}
std::vector<magnetism::Pole> packed_poles(int nx, int ny, int nz) {
  return as_poles(layouts::packed_bars(nx, ny, nz));
}

std::vector<multipole::Source> as_sources(const std::vector<magnetism::Pole>& poles) {
  std::vector<multipole::Source> s;
  for (const auto& p : poles) s.push_back({p.position, p.strength, p.body});
  return s;
}

/// The previous direct sum: each pair once, scalar (pole_model.cpp's loop,
/// which still serves fewer than kSimdDirectPoles poles).
void previous_direct(const std::vector<magnetism::Pole>& poles, double eps, std::vector<Vec3>& f) {
  for (std::size_t i = 0; i < poles.size(); ++i)
    for (std::size_t j = i + 1; j < poles.size(); ++j) {
      if (poles[j].body == poles[i].body) continue;
      const Vec3 fij = magnetism::pole_pair_force(poles[i].strength, poles[i].position,
                                                  poles[j].strength, poles[j].position, eps);
      f[j] += fij;
      f[i] -= fij;
    }
}

/// Net force on each magnet from its poles' forces (or kernel sums x strength).
std::vector<Vec3> magnet_forces(const std::vector<magnetism::Pole>& poles,
                                const std::vector<Vec3>& pole_force) {
  std::vector<Vec3> f(poles.size() / 2);
  for (std::size_t i = 0; i < poles.size(); ++i) f[poles[i].body] += pole_force[i];
  return f;
}

struct KernelRow {
  int n = 0;
  double prev_tree = 0, tree = 0, prev_direct = NAN, direct = 0;
  double prev_error = 0, error = 0;
  double fmm = NAN, fmm_error = NAN;  ///< the fast multipole method at its defaults
  /// The FMM as session 18 left it (the same theta, order and leaves, every
  /// translation at the full order: SummationOptions::fmm_pair_orders off), same run.
  double prev_fmm = NAN, prev_fmm_error = NAN;
  multipole::FmmProfile profile;  ///< the current FMM's phases, one evaluation
  /// The FMM reusing its cells and lists between calls (FmmOptions::reuse)
  /// while every magnet moves 2 mm back and forth, and its error.
  double fmm_reuse = NAN, fmm_reuse_error = NAN;
};

/// Previous and current tree, previous and current direct sum, on n random magnets.
KernelRow magnet_kernels(int n, double budget) {
  using namespace alloy::magnetism;
  constexpr double eps = 0.005;
  const auto poles = random_poles(n, 1);
  const auto sources = as_sources(poles);
  KernelRow r{.n = n};
  std::vector<Vec3> exact(poles.size()), f(poles.size()), k(poles.size());
  r.direct = cpu_per_call(
      [&] {
        std::fill(exact.begin(), exact.end(), Vec3{});
        accumulate_pole_forces(poles, eps, exact, {.method = Summation::Direct});
      },
      budget);
  // The previous direct sum is quadratic and scalar: once is enough past 3,000.
  r.prev_direct = cpu_per_call(
      [&] {
        std::fill(f.begin(), f.end(), Vec3{});
        previous_direct(poles, eps, f);
      },
      n > 3000 ? 0 : budget);
  multipole::Tree previous;
  r.prev_tree = cpu_per_call(
      [&] {
        previous.build(sources, eps, {.theta = 0.25, .leaf_size = 8});
        previous.evaluate_at_sources_per_group(k);
      },
      n > 3000 ? 0 : budget);
  for (std::size_t i = 0; i < poles.size(); ++i) k[i] = k[i] * (kMu0Over4Pi * poles[i].strength);
  r.prev_error = rms_relative(magnet_forces(poles, k), magnet_forces(poles, exact));
  multipole::Tree tree;
  r.tree = cpu_per_call(
      [&] {
        std::fill(f.begin(), f.end(), Vec3{});
        accumulate_pole_forces(poles, eps, f, {.method = Summation::Tree}, &tree);
      },
      budget);
  r.error = rms_relative(magnet_forces(poles, f), magnet_forces(poles, exact));
  multipole::Tree fmm;
  r.fmm = cpu_per_call(
      [&] {
        std::fill(f.begin(), f.end(), Vec3{});
        accumulate_pole_forces(poles, eps, f, {.method = Summation::Fmm, .theta = kFmmTheta}, &fmm);
      },
      budget);
  r.fmm_error = rms_relative(magnet_forces(poles, f), magnet_forces(poles, exact));
  // The phases of one evaluation (multipole::Fmm directly, on the same
  // sources): the mean of three after a first (its allocations and cold
  // caches left out).
  {
    multipole::Fmm one;
    const multipole::FmmOptions o{.theta = kFmmTheta,
                                  .order = kFmmOrder,
                                  .leaf_size = 64,
                                  .single_near = true,
                                  .pair_orders = true};
    one.build(sources, eps, o);
    one.evaluate_at_sources(k);
    const multipole::FmmProfile first = one.profile();
    for (int rep = 0; rep < 3; ++rep) {
      one.build(sources, eps, o);
      one.evaluate_at_sources(k);
    }
    const multipole::FmmProfile& all = one.profile();
    r.profile = {(all.tree - first.tree) / 3, (all.upward - first.upward) / 3,
                 (all.walk - first.walk) / 3, (all.m2l - first.m2l) / 3,
                 (all.near - first.near) / 3, (all.downward - first.downward) / 3};
  }
  // Reuse between steps: the magnets moved 2 mm (whole, a random direction
  // each) and back, alternately, as bodies that move little between steps.
  {
    std::mt19937_64 rng(5);
    std::vector<multipole::Source> moved = sources;
    std::vector<Vec3> shift(static_cast<std::size_t>(n));
    for (Vec3& v : shift) v = layouts::random_direction(rng) * 0.002;
    for (multipole::Source& s : moved) s.position += shift[s.group];
    multipole::Fmm reuse;
    const multipole::FmmOptions o{.theta = kFmmTheta,
                                  .order = kFmmOrder,
                                  .leaf_size = 64,
                                  .single_near = true,
                                  .reuse = true,
                                  .pair_orders = true};
    reuse.build(sources, eps, o);
    reuse.evaluate_at_sources(k);
    int call = 0;
    r.fmm_reuse = cpu_per_call(
        [&] {
          reuse.build(++call % 2 ? moved : sources, eps, o);
          reuse.evaluate_at_sources(k);
        },
        budget);
    std::vector<Vec3> exact_here(poles.size());
    multipole::direct_at_sources(call % 2 ? moved : sources, eps, exact_here);
    for (std::size_t i = 0; i < poles.size(); ++i) {
      k[i] = k[i] * (kMu0Over4Pi * poles[i].strength);
      exact_here[i] = exact_here[i] * (kMu0Over4Pi * poles[i].strength);
    }
    r.fmm_reuse_error = rms_relative(magnet_forces(poles, k), magnet_forces(poles, exact_here));
  }
  // Session 18's FMM, same run: the same settings, every translation at the
  // full order.
  {
    multipole::Tree old;
    r.prev_fmm = cpu_per_call(
        [&] {
          std::fill(f.begin(), f.end(), Vec3{});
          accumulate_pole_forces(
              poles, eps, f,
              {.method = Summation::Fmm, .theta = kFmmTheta, .fmm_pair_orders = false}, &old);
        },
        budget);
    r.prev_fmm_error = rms_relative(magnet_forces(poles, f), magnet_forces(poles, exact));
  }
  return r;
}

/// (theta, order, RMS relative force error, ms) of the FMM on the packed block.
std::vector<std::array<double, 4>> packed_sweep_fmm(int nx, int ny, int nz) {
  using namespace alloy::magnetism;
  const auto poles = packed_poles(nx, ny, nz);
  std::vector<Vec3> exact(poles.size());
  accumulate_pole_forces(poles, 0.005, exact, {.method = Summation::Direct});
  std::vector<std::array<double, 4>> out;
  for (auto [theta, order] :
       {std::pair{kFmmTheta, kFmmOrder}, {0.7, 4}, {0.5, 4}, {0.5, 6}, {0.4, 6}}) {
    std::vector<Vec3> f(poles.size());
    const double c0 = cpu_seconds();
    accumulate_pole_forces(poles, 0.005, f,
                           {.method = Summation::Fmm, .theta = theta, .fmm_order = order});
    const double t = cpu_seconds() - c0;
    out.push_back({theta, double(order),
                   rms_relative(magnet_forces(poles, f), magnet_forces(poles, exact)), t});
  }
  return out;
}

/// (theta, RMS relative force error, ms) of the current tree on a packed block
/// of aligned bars: the table theta_for_tolerance is read from.
std::vector<std::array<double, 3>> packed_sweep(int nx, int ny, int nz) {
  using namespace alloy::magnetism;
  const auto poles = packed_poles(nx, ny, nz);
  std::vector<Vec3> exact(poles.size());
  accumulate_pole_forces(poles, 0.005, exact, {.method = Summation::Direct});
  std::vector<std::array<double, 3>> out;
  for (double theta : {0.2, 0.25, 0.3, 0.35, 0.4, 0.5}) {
    std::vector<Vec3> f(poles.size());
    const double c0 = cpu_seconds();
    accumulate_pole_forces(poles, 0.005, f, {.method = Summation::Tree, .theta = theta});
    const double t = cpu_seconds() - c0;
    out.push_back({theta, rms_relative(magnet_forces(poles, f), magnet_forces(poles, exact)), t});
  }
  return out;
}

/// gravity.nbody's sum on n bodies, as the stage runs it now and as it ran
/// in session 16 (same run), with the direct sum as the reference.
struct GravityRow {
  int n = 0;
  double direct = NAN;    ///< the direct sum (the exact reference), CPU s
  double previous = NAN;  ///< session 16: the walk at theta 0.5 below 4,000, FMM order 5 from it
  double current = NAN;   ///< now: the walk at kWalkTheta below kFmmFromMasses, the FMM from it
  double previous_error = 0;  ///< RMS relative error against the direct sum
  double current_error = 0;
  const char* method = "";  ///< the current method at n
};

/// The rows above on the bench scene's grid (1 m apart, 1,000 kg) or on a
/// Gaussian cluster.
GravityRow gravity_kernels(int n, bool cluster, double budget) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0, std::cbrt(double(n)));
  const int s = cube_side(n);
  std::vector<Vec3> x(n);
  std::vector<double> m(n, 1e3);
  for (int i = 0; i < n; ++i)
    x[i] = cluster ? Vec3{g(rng), g(rng), g(rng)}
                   : Vec3{1.0 * (i % s), 1.0 * (i / s % s), 1.0 * (i / (s * s))};
  GravityRow r{.n = n};
  std::vector<Vec3> exact(n), a(n);
  constexpr double G = gravity::kGravitationalConstant, eps = 0.0;
  r.direct =
      cpu_per_call([&] { gravity::accelerations(x, x, m, G, eps, exact); }, n > 3000 ? 0 : budget);
  multipole::Tree tree;
  const bool fmm_before = n >= 4000, fmm_now = std::size_t(n) >= gravity::kFmmFromMasses;
  r.previous = cpu_per_call(
      [&] {
        if (fmm_before)
          gravity::tree_accelerations(x, m, G, eps, tree, a, 0.55, 5, 48);
        else
          gravity::tree_accelerations(x, m, G, eps, tree, a, 0.5, 0, 64);
      },
      budget);
  r.previous_error = rms_relative(a, exact);
  r.current = cpu_per_call(
      [&] {
        if (fmm_now)
          gravity::tree_accelerations(x, m, G, eps, tree, a);
        else
          gravity::tree_accelerations(x, m, G, eps, tree, a, gravity::kWalkTheta, 0,
                                      gravity::kWalkLeaf);
      },
      budget);
  r.current_error = rms_relative(a, exact);
  r.method = fmm_now ? "FMM" : "walk";
  return r;
}

/// Issue 16's goals for parts 1 and 2, previous against current; `stage_ms`:
/// the magnetic_forces and gravity.nbody stages at 10,000 from the sweep
/// above (NaN if not measured). Appends to `md`.
void issue16_kernels(bool magnets, bool gravity, bool quick, double stage_magnets_ms,
                     double stage_magnets_error, double stage_gravity_ms, std::string& md) {
  const double budget = quick ? 0.01 : 0.2;
  auto pm = [](bool ok) { return ok ? std::string("pass") : std::string("miss"); };
  md += "\nKernels alone (no world), CPU ms per evaluation, SIMD kernel: `" +
        std::string(multipole::direct_kernel_isa()) + "`.\n";
  if (magnets) {
    const std::vector<int> ns =
        quick ? std::vector<int>{100, 300} : std::vector<int>{100, 300, 500, 1000, 3000, 10000};
    std::vector<KernelRow> rows;
    for (int n : ns) rows.push_back(magnet_kernels(n, budget));
    Table t({"magnets", "previous tree (theta 0.25)", "tree", "ratio", "previous direct",
             "direct (SIMD)", "ratio", "pairs/s (SIMD)", "RMS error previous", "RMS error"});
    Table tf({"magnets", "direct (SIMD)", "tree", "FMM (session 18)", "FMM", "FMM / previous FMM",
              "FMM / direct", "FMM / tree", "RMS error tree", "RMS error FMM (session 18)",
              "RMS error FMM", "FMM reused", "reused / FMM", "RMS error reused"});
    for (const KernelRow& r : rows) {
      const double pairs = 4.0 * r.n * r.n;  // ordered pole pairs
      t.row({std::to_string(r.n), fmt(1e3 * r.prev_tree), fmt(1e3 * r.tree),
             fmt(r.prev_tree / r.tree, 3) + "x", fmt(1e3 * r.prev_direct), fmt(1e3 * r.direct),
             fmt(r.prev_direct / r.direct, 3) + "x", fmt(pairs / r.direct, 3), fmt(r.prev_error),
             fmt(r.error)});
      tf.row({std::to_string(r.n), fmt(1e3 * r.direct), fmt(1e3 * r.tree), fmt(1e3 * r.prev_fmm),
              fmt(1e3 * r.fmm), fmt(r.fmm / r.prev_fmm, 3), fmt(r.fmm / r.direct, 3),
              fmt(r.fmm / r.tree, 3), fmt(r.error), fmt(r.prev_fmm_error), fmt(r.fmm_error),
              fmt(1e3 * r.fmm_reuse), fmt(r.fmm_reuse / r.fmm, 3), fmt(r.fmm_reuse_error)});
    }
    md += "\nmagnetic forces on random magnets (tree at the default tolerance 1e-3, theta " +
          fmt(magnetism::kDefaultTheta) + ", leaves of 64, blocks of 32 poles):\n\n" + t.str();
    md += "\nThe fast multipole method (method \"fmm\": theta " + fmt(magnetism::kFmmTheta) +
          ", order " + std::to_string(magnetism::kFmmOrder) +
          ", leaves of 64; each translation at the lowest order its pair's separation allows, "
          "in eight-lane batches; the near field in single precision) against session 18's "
          "(every translation at the full order), the tree and the direct sum, same run "
          "(ratios: below 1 is faster):\n\n" +
          tf.str();
    for (const KernelRow& row : rows) {
      if (row.n != 500 && row.n != rows.back().n) continue;
      const multipole::FmmProfile& p = row.profile;
      const double T = p.total();
      auto pc = [&](double x) { return fmt(100 * x / T, 2) + " %"; };
      md += "\nWhere the FMM's time goes at " + std::to_string(row.n) +
            " magnets (one evaluation, the mean of three, CPU " + fmt(1e3 * T) + " ms): tree " +
            pc(p.tree) + ", multipoles (P2M, M2M) " + pc(p.upward) + ", walk " + pc(p.walk) +
            ", translations (M2L) " + pc(p.m2l) + ", near field (P2P) " + pc(p.near) +
            ", local expansions down and out (L2L, L2P) " + pc(p.downward) + ".\n";
    }
    // Crossover of the current tree (and of the FMM) with the current direct sum.
    // Already faster at the smallest n: the crossover is at or below it
    // (printed as that n).
    auto crossover = [&](auto fast) {
      double cross = fast(rows[0]) < rows[0].direct ? double(rows[0].n) : NAN;
      for (std::size_t i = 1; i < rows.size(); ++i) {
        const double ra = std::log(fast(rows[i - 1]) / rows[i - 1].direct),
                     rb = std::log(fast(rows[i]) / rows[i].direct);
        if (ra >= 0 && rb < 0)
          cross = std::exp(std::log(rows[i - 1].n) +
                           ra / (ra - rb) * (std::log(rows[i].n) - std::log(rows[i - 1].n)));
      }
      return cross;
    };
    auto cross_text = [&](double c) {
      if (!std::isfinite(c)) return std::string("not reached");
      if (c == double(rows[0].n)) return "at or below " + std::to_string(rows[0].n);
      return fmt(c, 2);
    };
    const double cross = crossover([](const KernelRow& r) { return r.tree; });
    const double cross_fmm = crossover([](const KernelRow& r) { return r.fmm; });
    if (!quick) {
      const auto sweep = packed_sweep(25, 20, 20);
      Table p({"theta", "RMS relative force error", "ms"});
      for (const auto& [theta, e, ms] : sweep) p.row({fmt(theta), fmt(e), fmt(1e3 * ms)});
      md += "\nPacked block of 10,000 aligned bars (25 x 20 x 20, touching), current tree:\n\n" +
            p.str();
      Table pf({"theta", "order", "RMS relative force error", "ms"});
      for (const auto& [theta, order, e, ms] : packed_sweep_fmm(25, 20, 20))
        pf.row({fmt(theta), fmt(order), fmt(e), fmt(1e3 * ms)});
      md += "\nThe same block with the FMM:\n\n" + pf.str();
    }
    const KernelRow& big = rows.back();
    if (big.n == 10000) {
      md += "\nGoals (issue 16, part 1), at 10,000 magnets:\n\n";
      md += "- magnetic_forces stage (method \"auto\", as a user runs it) at most 10 ms a step: " +
            (std::isfinite(stage_magnets_ms)
                 ? fmt(stage_magnets_ms) + " ms, " + pm(stage_magnets_ms <= 10)
                 : std::string("stage not measured")) +
            "; the tree's summation alone " + fmt(1e3 * big.tree) + " ms (previous tree " +
            fmt(1e3 * big.prev_tree) + " ms, " + fmt(big.prev_tree / big.tree, 3) + "x), " +
            pm(1e3 * big.tree <= 10) + ".\n";
      md += "- the FMM's summation alone at most 10 ms: " + fmt(1e3 * big.fmm) + " ms (" +
            fmt(big.fmm / big.prev_fmm, 3) + " of session 18's, " + fmt(big.fmm / big.tree, 3) +
            " of the tree's time, " + fmt(big.fmm / big.direct, 3) + " of the direct sum's), " +
            pm(1e3 * big.fmm <= 10) +
            "; reusing its cells and lists between steps (magnets moving 2 mm) " +
            fmt(1e3 * big.fmm_reuse) + " ms, " + pm(1e3 * big.fmm_reuse <= 10) + ", error " +
            fmt(big.fmm_reuse_error) + "; its RMS error " + fmt(big.fmm_error) +
            " (random; see the packed block above), " + pm(big.fmm_error <= 1e-3) +
            "; crossover with the direct sum " + cross_text(cross_fmm) + ", " +
            pm(std::isfinite(cross_fmm) && cross_fmm <= 500) + ".\n";
      md += "- RMS relative force error at most 1e-3 (the stage, method \"auto\"): " +
            fmt(stage_magnets_error) + ", " + pm(stage_magnets_error <= 1e-3) + "; the tree's " +
            fmt(big.error) + " (previous " + fmt(big.prev_error) + ").\n";
      md +=
          "- crossover with the direct sum at or below 500 magnets (the FMM, auto's method "
          "from " +
          std::to_string(magnetism::kFmmAutoPoles / 2) + " magnets): " + cross_text(cross_fmm) +
          ", " + pm(std::isfinite(cross_fmm) && cross_fmm <= 500) + "; the tree's " +
          cross_text(cross) + ".\n";
      const double rate = 4.0 * big.n * big.n / big.direct,
                   prev_rate = 4.0 * big.n * big.n / big.prev_direct;
      md += "- direct kernel at least 8e8 pair interactions a second: " + fmt(rate, 3) + ", " +
            pm(rate >= 8e8) + " (previous " + fmt(prev_rate, 3) + ", each pair once).\n";
    }
  }
  if (gravity) {
    const std::vector<int> ns =
        quick ? std::vector<int>{100, 300} : std::vector<int>{300, 1000, 3000, 10000};
    Table t({"bodies", "layout", "direct", "session 16", "now", "method now", "now / session 16",
             "RMS error session 16", "RMS error now"});
    GravityRow big;
    for (int n : ns)
      for (bool cluster : {false, true}) {
        const GravityRow r = gravity_kernels(n, cluster, budget);
        t.row({std::to_string(n), cluster ? "Gaussian cluster" : "grid", fmt(1e3 * r.direct),
               fmt(1e3 * r.previous), fmt(1e3 * r.current), r.method,
               fmt(r.current / r.previous, 3), fmt(r.previous_error), fmt(r.current_error)});
        if (n == 10000 && !cluster) big = r;
      }
    md +=
        "\ngravity.nbody's sum as the stage runs it (session 16: the walk at theta 0.5, leaves "
        "of 64, below 4,000 masses, the FMM at theta 0.55, order 5, leaves of 48 from there; "
        "now: the walk at theta " +
        fmt(gravity::kWalkTheta) + " from " + std::to_string(gravity::kTreeFromMasses) +
        " masses, the FMM at theta " + fmt(gravity::kTreeTheta) + ", order " +
        std::to_string(gravity::kTreeOrder) + ", leaves of " + std::to_string(gravity::kTreeLeaf) +
        " from " + std::to_string(gravity::kFmmFromMasses) + "; error bound " +
        fmt(gravity::kErrorBound) + "), CPU ms:\n\n" + t.str();
    if (big.n == 10000)
      md += "\nGoal (issue 16, part 2): gravity.nbody at 10,000 bodies at most 10 ms a step: " +
            (std::isfinite(stage_gravity_ms)
                 ? fmt(stage_gravity_ms) + " ms (stage), " + pm(stage_gravity_ms <= 10)
                 : std::string("stage not measured")) +
            "; the sum alone " + fmt(1e3 * big.current) + " ms, " + pm(1e3 * big.current <= 10) +
            ", error " + fmt(big.current_error) + " (bound " + fmt(gravity::kErrorBound) + ", " +
            pm(big.current_error <= gravity::kErrorBound) + "), against session 16's " +
            fmt(1e3 * big.previous) + " ms (" + fmt(big.current / big.previous, 3) + "x, error " +
            fmt(big.previous_error) + ") and the direct sum's " + fmt(1e3 * big.direct) +
            " ms. The space scene has fewer than " + std::to_string(gravity::kTreeFromMasses) +
            " masses and keeps the direct sum: its bits, and so its energy drift, are unchanged "
            "(golden hashes).\n";
  }
}

}  // namespace

/// --ladder: the 10,000-element ladder alone, at the settings a user gets
/// (4 substeps, the default dense limit) and with 1 substep, each timed over
/// 400 steps in CPU seconds (the whole step of a world that holds only the
/// electricity resolver, and the stage's own share): a quick figure to work
/// on the goal with, and to profile (perf record on this mode sees the stage
/// and nothing else).
void ladder_only() {
  for (int substeps : {4, 1}) {
    WorldDef d = def_with({"electricity"});
    if (substeps != 4) d.settings["electricity"].set("substeps", std::int64_t(substeps));
    scenes::Sim sim(d);
    World& w = *sim;
    build_ladder(w, 10000);
    w.start();
    w.run(20);
    const Timed t = time_steps(w, 1e9, 400);
    std::printf(
        "ladder of 10,000 elements, %d substep%s: %s ms a step (stage), %s ms (whole step)\n",
        substeps, substeps > 1 ? "s" : "", fmt(1e3 * t.per_step.at("electricity")).c_str(),
        fmt(1e3 * t.per_step.at(kWholeStep)).c_str());
  }
}

int main(int argc, char** argv) {
  Options opt =
      Options::parse(argc, argv, "alloy_bench_scaling",
                     {"--electricity", "--collisions", "--magnets", "--gravity", "--ladder"});
  if (opt.flag("--ladder")) {
    ladder_only();
    return 0;
  }
  // A filter runs only the rows it names and writes nothing.
  const bool only_electricity = opt.flag("--electricity"),
             only_collisions = opt.flag("--collisions");
  const bool only_magnets = opt.flag("--magnets"), only_gravity = opt.flag("--gravity");
  const bool filtered = only_electricity || only_collisions || only_magnets || only_gravity;
  if (filtered) opt.docs.clear();
  const std::vector<int> ns =
      opt.quick ? std::vector<int>{10, 30, 100, 300}
                : std::vector<int>{10, 30, 100, 300, 1000, 3000, 10000, 30000, 100000};
  const double budget = opt.quick ? 0.02 : 0.3;
  const int max_steps = opt.quick ? 20 : 200;

  std::vector<Line> lines;
  auto line = [&](std::string label, std::string stage, std::string expected) {
    lines.push_back({std::move(label), std::move(stage), std::move(expected), {}, {}, {}});
    return lines.size() - 1;
  };
  const std::vector<std::string> rigid = {"rigid_body", "collisions", "gravity.uniform",
                                          "rigid_body_from_gravity", "rigid_body_from_collisions"};
  std::vector<Scene> scene_list;
  scene_list.push_back(
      {.name = "free",
       .def = def_with(rigid),
       .build = build_free,
       .lines = {line("rigid_body (no contacts)", "rigid_body", "linear"),
                 line("collisions (no contacts)", "collisions", "linear"),
                 line("gravity.uniform", "gravity.uniform", "linear"),
                 line("rigid_body_from_gravity", "rigid_body_from_gravity", "linear")}});
  scene_list.push_back(
      {.name = "resting",
       .def = def_with(rigid),
       .build = build_resting,
       .lines = {line("rigid_body (contacts)", "rigid_body", "linear"),
                 line("collisions (contacts)", "collisions", "linear"),
                 line("rigid_body_from_collisions", "rigid_body_from_collisions", "linear")},
       .warmup = 20});
  {
    WorldDef d = def_with({"rigid_body", "gravity.nbody", "rigid_body_from_gravity"});
    d.use["gravity"] = "gravity.nbody";
    scene_list.push_back({.name = "nbody",
                          .def = d,
                          .build = build_nbody,
                          .lines = {line("gravity.nbody", "gravity.nbody", "linear")}});
  }
  for (const char* method : {"dense", "sparse"}) {
    WorldDef d = def_with({"electricity"});
    d.settings["electricity"].set("dense_limit",
                                  std::int64_t(std::string(method) == "dense" ? 1 << 30 : 0));
    scene_list.push_back(
        {.name = std::string("ladder ") + method,
         .def = d,
         .build = build_ladder,
         .lines = {line(std::string(method) == "dense" ? "electricity (dense LU)"
                                                       : "electricity (sparse LDL^T)",
                        "electricity", std::string(method) == "dense" ? "quadratic" : "linear")},
         .warmup = 2,
         // Dense LU of 2n unknowns: n = 3000 would take minutes to factorise.
         .max_n = std::string(method) == "dense" ? 1000 : 1 << 30});
  }
  {
    // The same ladder with one substep a step (the `substeps` setting; its
    // coils' time constants are 50 ms and more, 200 steps): a quarter of the
    // solves. Its error against 4 substeps is measured below.
    WorldDef d = def_with({"electricity"});
    d.settings["electricity"].set("dense_limit", std::int64_t(0));
    d.settings["electricity"].set("substeps", std::int64_t(1));
    scene_list.push_back(
        {.name = "ladder 1 substep",
         .def = d,
         .build = build_ladder,
         .lines = {line("electricity (ladder, 1 substep)", "electricity", "linear")},
         .warmup = 2});
  }
  {
    WorldDef d = def_with({"electricity"});
    d.settings["electricity"].set("dense_limit", std::int64_t(0));
    scene_list.push_back(
        {.name = "ladder resistive",
         .def = d,
         .build = build_resistive_ladder,
         .lines = {line("electricity (resistive ladder)", "electricity", "linear")},
         .warmup = 2});
  }
  {
    WorldDef d = def_with({"electricity"});
    d.settings["electricity"].set("dense_limit", std::int64_t(0));
    scene_list.push_back({.name = "mesh",
                          .def = d,
                          .build = build_mesh,
                          .lines = {line("electricity (random mesh)", "electricity", "n log n")}});
  }
  {
    WorldDef d = def_with({"sound"});
    d.settings["sound"].set("max_voices", std::int64_t(100000));
    scene_list.push_back({.name = "voices",
                          .def = d,
                          .build = build_voices,
                          .lines = {line("sound (n voices)", "sound", "linear")},
                          .warmup = 1,
                          .after_start = strike_all});
  }
  scene_list.push_back(
      {.name = "mixed",
       .def = def_with({"rigid_body", "collisions", "gravity.uniform", "rigid_body_from_gravity",
                        "rigid_body_from_collisions", "magnetism", "magnetic_forces",
                        "rigid_body_from_magnetism", "electricity"}),
       .build = build_mixed,
       .lines = {line("whole step, mixed scene", kWholeStep, "n log n")},
       .warmup = 3});
  const std::size_t l_magnetism = line("magnetism", "magnetism", "linear");
  const std::size_t l_auto = line("magnetic_forces (auto)", "magnetic_forces", "linear");
  const std::size_t l_tree = line("magnetic_forces (tree)", "magnetic_forces", "n log n");
  const std::size_t l_direct = line("magnetic_forces (direct)", "magnetic_forces", "quadratic");
  const std::size_t l_rbm =
      line("rigid_body_from_magnetism", "rigid_body_from_magnetism", "linear");

  Progress progress("scaling", ns.size() * (scene_list.size() + 1), opt.progress);

  // 1. The scenes, stage by stage.
  std::vector<std::string> notes;
  auto wanted = [&](const Scene& sc) {
    if (!filtered) return true;
    const bool electric = sc.name.starts_with("ladder") || sc.name == "mesh";
    const bool colliding = sc.name == "free" || sc.name == "resting";
    return (only_electricity && electric) || (only_collisions && colliding) ||
           (only_gravity && sc.name == "nbody");
  };
  for (const Scene& sc : scene_list) {
    if (!wanted(sc)) continue;
    for (int n : ns) {
      progress.tick();
      if (n > sc.max_n) {
        for (std::size_t li : sc.lines)
          lines[li].skipped.push_back("n = " + std::to_string(n) + ": not run (dense LU of " +
                                      std::to_string(2 * n) + "+ unknowns)");
        continue;
      }
      double predicted = 0;
      for (std::size_t li : sc.lines) predicted = std::max(predicted, predict(lines[li], n));
      if (predicted > (n > kLargeN ? kLargeSkipSeconds : kSkipSeconds)) {
        for (std::size_t li : sc.lines)
          lines[li].skipped.push_back("n = " + std::to_string(n) + ": skipped (predicted " +
                                      fmt(predicted) + " s per step)");
        continue;
      }
      scenes::Sim sim(sc.def);
      World& w = *sim;
      sc.build(w, n);
      w.start();
      if (sc.after_start) sc.after_start(w);
      w.run(n > kLargeN ? std::min(sc.warmup, kLargeWarmup) : sc.warmup);
      const Timed t = time_steps(w, budget, n > kLargeN ? kLargeSteps : max_steps);
      for (std::size_t li : sc.lines) {
        const auto it = t.per_step.find(lines[li].stage);
        if (it == t.per_step.end()) continue;
        lines[li].n.push_back(n);
        lines[li].seconds.push_back(it->second);
      }
    }
  }

  // 2. The magnets: after one step, the error of the tree against the direct
  //    sum on the same poles; then the same world timed with the tree, then
  //    with the direct sum.
  std::vector<MagneticPoint> mag;
  const double theta = magnetism::kDefaultTheta;
  for (int n : filtered && !only_magnets ? std::vector<int>{} : ns) {
    progress.tick();
    // The magnets' rows stop at 10,000: above, the direct sum (and the error
    // check against it) would take minutes a step with the present methods.
    if (n > kLargeN) continue;
    // The stage's defaults (method "auto"), as a user runs it; the tree and
    // the direct sum are then set on the same world for comparison.
    WorldDef d =
        def_with({"rigid_body", "magnetism", "magnetic_forces", "rigid_body_from_magnetism"});
    scenes::Sim sim(d);
    World& w = *sim;
    build_magnets(w, n);
    w.start();
    w.run(1);
    auto& forces = dynamic_cast<magnetism::MagneticForces&>(*w.stage("magnetic_forces"));
    MagneticPoint p{.n = double(n)};
    const magnetism::SummationOptions as_user = forces.summation();
    {
      // The error, on the configuration after one step (the same whatever the
      // timing does later): direct, then auto, then tree, on the same poles.
      std::vector<Vec3> exact_f, exact_t, approx_f, approx_t;
      forces.set_summation({.method = magnetism::Summation::Direct});
      forces.update(w.view());
      for (const auto& b : forces.bodies()) exact_f.push_back(b.force), exact_t.push_back(b.torque);
      for (int k = 0; k < 2; ++k) {
        if (k == 0)
          forces.set_summation(as_user);
        else
          forces.set_summation({.method = magnetism::Summation::Tree, .theta = theta});
        forces.update(w.view());
        approx_f.clear(), approx_t.clear();
        for (const auto& b : forces.bodies())
          approx_f.push_back(b.force), approx_t.push_back(b.torque);
        (k ? p.error : p.auto_error) = rms_relative(approx_f, exact_f);
        (k ? p.torque_error : p.auto_torque_error) = rms_relative(approx_t, exact_t);
      }
    }
    // Session 18's stage, then the stage as a user runs it (same world; the
    // magnets move on meanwhile, a few millimetres).
    if (n * 2 >= magnetism::kFmmAutoPoles) {
      magnetism::SummationOptions previous = as_user;
      previous.fmm_pair_orders = false;
      previous.check_every = 1;
      forces.set_summation(previous);
      p.previous_auto = time_steps(w, budget, max_steps).per_step.at("magnetic_forces");
    }
    forces.set_summation(as_user);
    const std::uint64_t checks0 = forces.checks(), updates0 = forces.updates();
    const Timed ta = time_steps(w, budget, max_steps);
    if (forces.updates() > updates0)
      p.checked_share = double(forces.checks() - checks0) / double(forces.updates() - updates0);
    p.automatic = ta.per_step.at("magnetic_forces");
    p.auto_method = forces.used_method() == magnetism::Summation::Fmm    ? "FMM"
                    : forces.used_method() == magnetism::Summation::Tree ? "tree"
                                                                         : "direct";
    p.check_error = forces.last_check_error();
    for (auto [li, stage] :
         {std::pair{l_magnetism, "magnetism"}, std::pair{l_rbm, "rigid_body_from_magnetism"}}) {
      lines[li].n.push_back(n);
      lines[li].seconds.push_back(ta.per_step.at(stage));
    }
    lines[l_auto].n.push_back(n);
    lines[l_auto].seconds.push_back(p.automatic);
    if (forces.used_method() == magnetism::Summation::Fmm) {
      // What the stage costs beyond the summation: the FMM alone on the
      // stage's own poles, and the check alone, each timed on its own.
      const std::vector<magnetism::Pole> poles(forces.poles().begin(), forces.poles().end());
      std::vector<Vec3> f(poles.size());
      multipole::Tree ws;
      p.sum_alone = cpu_per_call(
          [&] {
            std::fill(f.begin(), f.end(), Vec3{});
            magnetism::accumulate_pole_forces(
                poles, forces.softening(), f,
                {.method = magnetism::Summation::Fmm, .theta = magnetism::kFmmTheta}, &ws);
          },
          budget);
      p.check = cpu_per_call(
          [&] {
            volatile double e =
                magnetism::sampled_force_error(poles, forces.bodies(), f, forces.softening());
            (void)e;
          },
          budget / 4);
    }

    forces.set_summation({.method = magnetism::Summation::Tree, .theta = theta});
    const Timed tt = time_steps(w, budget, max_steps);
    p.tree = tt.per_step.at("magnetic_forces");
    lines[l_tree].n.push_back(n);
    lines[l_tree].seconds.push_back(p.tree);

    const double predicted = predict(lines[l_direct], n);
    if (predicted > kSkipSeconds) {
      p.direct_skipped = true;
      lines[l_direct].skipped.push_back("n = " + std::to_string(n) + ": skipped (predicted " +
                                        fmt(predicted) + " s per step)");
    } else {
      forces.set_summation({.method = magnetism::Summation::Direct});
      // One step at most at the largest n: the direct sum is the slow one.
      const Timed td = time_steps(w, budget, predicted > 1 ? 1 : max_steps);
      p.direct = td.per_step.at("magnetic_forces");
      lines[l_direct].n.push_back(n);
      lines[l_direct].seconds.push_back(p.direct);
    }
    mag.push_back(p);
  }
  // Where the tree starts to win: log-log interpolation between the last n
  // where direct was faster and the first where the tree was.
  double crossover = NAN;
  for (std::size_t i = 1; i < mag.size(); ++i) {
    const MagneticPoint &a = mag[i - 1], &b = mag[i];
    if (a.direct_skipped || b.direct_skipped) continue;
    const double ra = std::log(a.tree / a.direct), rb = std::log(b.tree / b.direct);
    if (ra >= 0 && rb < 0) {
      const double f = ra / (ra - rb);
      crossover = std::exp(std::log(a.n) + f * (std::log(b.n) - std::log(a.n)));
    }
  }
  double packed = NAN;
  if (!opt.quick && !filtered) packed = packed_error(25, 20, 20, theta);

  // 2b. The circuits' sparse solvers, previous against current, on the same networks.
  std::vector<SolverPoint> solver_points;
  if (!only_collisions && !only_magnets && !only_gravity)
    for (int n : opt.quick ? std::vector<int>{100, 300} : std::vector<int>{1000, 10000}) {
      solver_points.push_back(compare_solvers("ladder", build_ladder, n, budget));
      solver_points.push_back(compare_solvers("mesh", build_mesh, n, budget));
    }

  // 3. Output.
  if (!filtered) {
    Csv csv(opt.file("scaling.csv"),
            {"stage", "expected", "n", "seconds_per_step", "fitted_slope_upper_half"});
    for (const Line& l : lines) {
      const double s = upper_slope(l);
      for (std::size_t i = 0; i < l.n.size(); ++i)
        csv.row({l.label, l.expected, Csv::cell(l.n[i]), Csv::cell(l.seconds[i]), Csv::cell(s)});
    }
  }
  if (!filtered) {
    Csv csv(opt.file("magnetic_crossover.csv"),
            {"magnets", "direct_seconds_per_step", "tree_seconds_per_step", "theta",
             "rms_relative_force_error", "rms_relative_torque_error"});
    for (const MagneticPoint& p : mag)
      csv.row({Csv::cell(p.n), p.direct_skipped ? "" : Csv::cell(p.direct), Csv::cell(p.tree),
               Csv::cell(theta), Csv::cell(p.error), Csv::cell(p.torque_error)});
  }
  if (!filtered) {
    Plot plot{.title = "Time per step against the number of objects",
              .x_label = "objects n",
              .y_label = "CPU time per step (s)"};
    for (const Line& l : lines)
      plot.series.push_back(
          {.name = l.label, .x = l.n, .y = l.seconds, .dashed = l.expected == "quadratic"});
    write_svg(plot, opt.file("scaling.svg"));
  }
  if (!filtered) {
    Plot plot{.title = "magnetic_forces: direct sum against Barnes-Hut tree",
              .x_label = "magnets n",
              .y_label = "CPU time per step of magnetic_forces (s)"};
    Series d{.name = "direct (every pole pair)"}, t{.name = "tree, theta " + fmt(theta)};
    for (const MagneticPoint& p : mag) {
      if (!p.direct_skipped) d.x.push_back(p.n), d.y.push_back(p.direct);
      t.x.push_back(p.n), t.y.push_back(p.tree);
    }
    plot.series = {d, t};
    if (std::isfinite(crossover)) {
      // The crossover on the direct line (interpolated in log-log).
      for (std::size_t i = 1; i < d.x.size(); ++i)
        if (d.x[i - 1] <= crossover && crossover <= d.x[i]) {
          const double f = std::log(crossover / d.x[i - 1]) / std::log(d.x[i] / d.x[i - 1]);
          const double y = std::exp(std::log(d.y[i - 1]) + f * std::log(d.y[i] / d.y[i - 1]));
          plot.markers.push_back({crossover, y, "crossover n = " + fmt(crossover, 2)});
        }
    }
    write_svg(plot, opt.file("magnetic_crossover.svg"));
  }

  std::string md;
  {
    std::vector<std::string> header = {"stage", "expected"};
    for (int n : ns) header.push_back("n = " + std::to_string(n));
    header.push_back("slope (upper half)");
    header.push_back("measured class");
    Table table(header);
    for (const Line& l : lines) {
      if (filtered && l.n.empty()) continue;
      std::vector<std::string> row = {l.label, l.expected};
      for (int n : ns) {
        const auto it = std::find(l.n.begin(), l.n.end(), double(n));
        row.push_back(it == l.n.end() ? "-" : fmt(1e3 * l.seconds[it - l.n.begin()]));
      }
      const double s = upper_slope(l);
      row.push_back(std::isfinite(s) ? fmt(s, 2) : "-");
      row.push_back(growth_class(s));
      table.row(row);
    }
    md += "Milliseconds of CPU per step (dt = 1/240 s); `-`: not measured. Above n = " +
          std::to_string(kLargeN) + " a point gets at most " + std::to_string(kLargeWarmup) +
          " warm-up and " + std::to_string(kLargeSteps) +
          " timed steps, and is skipped if predicted slower than " + fmt(kLargeSkipSeconds) +
          " s a step.\n\n" + table.str();
    md += "\nWhy each stage grows as it does:\n\n";
    for (const Line& l : lines)
      if (!(filtered && l.n.empty()) && !growth_reason(l.label).empty())
        md += "- " + l.label + " (" + growth_class(upper_slope(l)) +
              "): " + growth_reason(l.label) + "\n";
    std::string skipped;
    for (const Line& l : lines)
      for (const std::string& s : l.skipped) skipped += "- " + l.label + ", " + s + "\n";
    if (!skipped.empty()) md += "\nNot measured:\n\n" + skipped;
  }
  if (!solver_points.empty()) {
    Table table({"network", "n", "unknowns (MNA)", "analyse + factor: LU / LDL^T",
                 "refactor: LU / LDL^T", "solve: LU / LDL^T", "max |dV| (V)"});
    auto ratio = [](const double(&v)[2]) {
      return fmt(v[0]) + " / " + fmt(v[1]) + " (" + fmt(v[0] / v[1], 2) + "x)";
    };
    for (const SolverPoint& p : solver_points)
      table.row({p.scene, std::to_string(p.n), std::to_string(p.unknowns), ratio(p.factor),
                 ratio(p.refactor), ratio(p.solve), fmt(p.max_difference)});
    md +=
        "\nCircuits, the sparse solver alone on the resolver's network (ms; LU: supernodal LU "
        "with COLAMD on the MNA matrix, the method before issue 16; LDL^T: the reduced "
        "Laplacian with AMD, symbolic analysis reused; refactor: same topology, new "
        "impedances; in brackets LU / LDL^T):\n\n" +
        table.str();
    // The ladder's 1 ms goal is judged with the others, at the end.
    // What fewer substeps cost in accuracy (a 1,000-element ladder: the
    // error is the coils' time constants against the substep, not n).
    const int steps[2] = {12, 60};
    std::string errors;
    for (int s : {4, 2, 1}) {
      errors += std::string(errors.empty() ? "" : "; ") + std::to_string(s) + " substep" +
                (s > 1 ? "s " : " ");
      for (int k = 0; k < 2; ++k)
        errors += std::string(k ? " / " : "") +
                  fmt(ladder_substep_error(opt.quick ? 100 : 1000, steps[k], s, 64));
    }
    md += "\nFewer substeps on the ladder (" + std::string(opt.quick ? "100" : "1,000") +
          " elements, L = 50 mH, R = 1 Ohm): the coil currents after 12 / 60 steps (50 / 250 "
          "ms) against 64 substeps, largest difference over the largest current: " +
          errors + ".\n";
  }
  if (!mag.empty()) {
    Table ta({"magnets", "auto ms/step", "session 18's auto ms/step", "auto / session 18",
              "auto took", "auto / tree", "auto / direct", "RMS rel. force error",
              "RMS rel. torque error", "its check's estimate", "FMM sum alone ms", "check alone ms",
              "updates checked", "the stage's own work ms"});
    for (const MagneticPoint& p : mag)
      ta.row({fmt(p.n), fmt(1e3 * p.automatic), fmt(1e3 * p.previous_auto),
              fmt(p.automatic / p.previous_auto, 3), p.auto_method, fmt(p.automatic / p.tree, 3),
              p.direct_skipped ? "-" : fmt(p.automatic / p.direct, 3), fmt(p.auto_error),
              fmt(p.auto_torque_error), fmt(p.check_error), fmt(1e3 * p.sum_alone),
              fmt(1e3 * p.check), fmt(p.checked_share, 2),
              fmt(1e3 * (p.automatic - p.sum_alone - p.checked_share * p.check))});
    md += "\nmagnetic_forces as a user runs it (method \"auto\", the default: direct below " +
          std::to_string(magnetism::kFmmAutoPoles / 2) +
          " magnets, the FMM from there with its check on " +
          std::to_string(magnetism::kAutoCheckParts) + " magnets at most every " +
          std::to_string(magnetism::kAutoCheckEvery) +
          " updates, the tree where the check fails), random magnets, against session 18's "
          "(every translation at the full order, the check every update) on the same world just "
          "before; the stage's own work is the stage less the FMM's sum and the check times the "
          "share of updates that ran it, each timed alone on the same poles:\n\n" +
          ta.str();
    Table table({"magnets", "direct ms/step", "tree ms/step", "direct / tree",
                 "RMS rel. force error", "RMS rel. torque error"});
    for (const MagneticPoint& p : mag)
      table.row({fmt(p.n), p.direct_skipped ? "-" : fmt(1e3 * p.direct), fmt(1e3 * p.tree),
                 p.direct_skipped ? "-" : fmt(p.direct / p.tree), fmt(p.error),
                 fmt(p.torque_error)});
    md += "\nmagnetic_forces with method \"tree\", theta = " + fmt(theta) +
          " (random magnets):\n\n" + table.str();
    md += "\nCrossover (tree faster from): n = " +
          (std::isfinite(crossover) ? fmt(crossover, 2) + " magnets" : std::string("not reached")) +
          "; `method = \"auto\"` leaves the direct sum at " +
          std::to_string(magnetism::kFmmAutoPoles / 2) + " magnets (" +
          std::to_string(magnetism::kFmmAutoPoles) +
          " poles) for the FMM, and falls back to "
          "the tree from " +
          std::to_string(magnetism::kTreeCrossoverPoles / 2) + " magnets.\n";
    if (std::isfinite(packed))
      md += "Packed block of 10,000 aligned bars (25 x 20 x 20, touching), theta " + fmt(theta) +
            ": RMS relative force error " + fmt(packed) + ".\n";
  }
  // Issue 16, parts 1 and 2: previous against current, and the goals.
  if (!filtered || only_magnets || only_gravity) {
    double stage_magnets = NAN, stage_magnets_error = NAN, stage_gravity = NAN;
    for (const MagneticPoint& p : mag)
      if (p.n == 10000) stage_magnets = 1e3 * p.automatic, stage_magnets_error = p.auto_error;
    for (const Line& l : lines)
      if (l.label == "gravity.nbody")
        for (std::size_t i = 0; i < l.n.size(); ++i)
          if (l.n[i] == 10000) stage_gravity = 1e3 * l.seconds[i];
    issue16_kernels(!filtered || only_magnets, !filtered || only_gravity, opt.quick, stage_magnets,
                    stage_magnets_error, stage_gravity, md);
  }
  // The goals of issue 16 (and issue 6's tree error), each pass or miss;
  // a goal whose rows were not run is not judged.
  struct Goal {
    std::string what, measured;
    bool pass;
  };
  std::vector<Goal> goals;
  auto at = [&](const std::string& label, double n) -> double {
    for (const Line& l : lines)
      if (l.label == label)
        for (std::size_t i = 0; i < l.n.size(); ++i)
          if (l.n[i] == n) return l.seconds[i];
    return NAN;
  };
  auto slope_of = [&](const std::string& label) {
    for (const Line& l : lines)
      if (l.label == label) return upper_slope(l);
    return double(NAN);
  };
  // The magnets' goals are judged by issue16_kernels above (previous method
  // against current), gravity's there too (with its sum alone) and here (the
  // stage); the scaling rows add the rest.
  if (const double t = at("gravity.nbody", 10000); std::isfinite(t))
    goals.push_back({"gravity.nbody, 10,000 bodies: at most 10 ms a step (the stage)",
                     fmt(1e3 * t) + " ms", t <= 10e-3});
  if (const double t = at("electricity (sparse LDL^T)", 10000); std::isfinite(t))
    goals.push_back({"electricity, ladder of 10,000 elements: at most 1 ms a step",
                     fmt(1e3 * t) + " ms", t <= 1e-3});
  for (const char* label : {"collisions (no contacts)", "collisions (contacts)"})
    if (const double t = at(label, 100000);
        std::isfinite(t) || (!opt.quick && (!filtered || only_collisions))) {
      const double sl = slope_of(label);
      goals.push_back({std::string(label) + ": near linear (slope below 1.25) to 100,000 bodies",
                       "slope " + fmt(sl, 2) + ", " +
                           (std::isfinite(t) ? fmt(1e3 * t) + " ms at 100,000" : "100,000 not run"),
                       std::isfinite(t) && sl < 1.25});
    }
  bool missed = false;
  if (!goals.empty()) {
    Table table({"goal", "measured", ""});
    for (const Goal& g : goals) {
      table.row({g.what, g.measured, g.pass ? "pass" : "miss"});
      missed = missed || !g.pass;
    }
    md += "\nGoals (issue 16; pass or miss in this run):\n\n" + table.str();
  }
  std::printf("%s", md.c_str());
  if (!opt.quick && !opt.docs.empty()) splice(opt.docs, "scaling", md);
  // Exit 1 on a missed goal (bench/run_all.sh lists it and goes on); a quick
  // run is a smoke test and judges nothing.
  return !opt.quick && missed ? 1 : 0;
}
