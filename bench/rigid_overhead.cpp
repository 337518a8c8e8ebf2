// Overhead of the harness on a rigid-body scene, as ratios measured in one run
// (issue 6, item 5):
//
//   harness / raw ODE        the world stepping a 1,000-box pile (rigid_body,
//                            collisions, the two interactions, gravity) against
//                            a loop written by hand over ODE with the same
//                            scene, solver, iterations, contact parameters,
//                            space type and step. Goal: <= 1.02.
//   all plugins / needed     the same scene in a registry with every native
//                            plugin (electricity, magnetism, ... unneeded here)
//                            against one holding only the five it needs.
//                            Goal: <= 1.01.
//
// The three variants are built side by side, let fall for 1 s (untimed), then
// stepped in lockstep: rounds of a few steps, each variant in turn (the order
// rotating), each round timed in CPU seconds. The variants are at the same
// simulated moment in each round, so a round's ratio compares the same work,
// and a slow moment of the shared machine falls on one round of one variant,
// not on a whole variant. Each ratio is the median of the rounds' ratios (the
// ratio of the summed times is printed beside it).
//
//   build/bench/alloy_bench_rigid [--quick] [--out DIR] [--docs FILE] [--no-progress]
//   build/bench/alloy_bench_rigid --profile STEPS   the harness variant alone,
//     settled, then STEPS steps inside CALLGRIND_START_INSTRUMENTATION, for
//     valgrind --tool=callgrind --instr-atstart=no (docs/performance.md).
//   build/bench/alloy_bench_rigid --profile-raw STEPS   the same for the raw ODE loop.
//   build/bench/alloy_bench_rigid --profile-impulses STEPS   the harness with a
//     reader of contact impulses (what the sound of strikes costs); the pose
//     digest must equal --profile's: impulses are read out, never fed back.
//
// Nothing in the pile reads impulses, so the harness computes none (no joint
// feedback), and the raw loop computes none either.
#include <ode/ode.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#endif

#include "bench/common/bench_common.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace {

using namespace alloy;

constexpr double kDt = 1.0 / 240.0;
constexpr double kG = 9.81;

// --- the baseline: ODE by hand ------------------------------------------------------

/// What a programmer writes with ODE alone: bodies with geoms, a hash space,
/// a near callback making contact joints, QuickStep, empty the group.
class RawOdePile {
 public:
  explicit RawOdePile(const scenes::PileLayout& layout) {
    dInitODE2(0);
    world_ = dWorldCreate();
    dWorldSetGravity(world_, 0, -kG, 0);
    dWorldSetERP(world_, cfg_.erp);
    dWorldSetCFM(world_, cfg_.cfm);
    dWorldSetQuickStepNumIterations(world_, cfg_.iterations);
    dWorldSetQuickStepW(world_, cfg_.sor);
    dWorldSetContactSurfaceLayer(world_, cfg_.surface_layer);
    dWorldSetContactMaxCorrectingVel(world_, cfg_.max_correcting_velocity);
    space_ = dHashSpaceCreate(nullptr);
    group_ = dJointGroupCreate(0);
    mu_ = std::sqrt(layout.friction * layout.friction);
    for (const auto& s : layout.statics) place(dCreateBox(space_, s.size.x, s.size.y, s.size.z), s);
    for (const auto& s : layout.boxes) {
      dBodyID b = dBodyCreate(world_);
      dMass m;
      dMassSetBoxTotal(&m, s.mass, s.size.x, s.size.y, s.size.z);
      dBodySetMass(b, &m);
      dBodySetFiniteRotationMode(b, 1);
      dGeomID g = dCreateBox(space_, s.size.x, s.size.y, s.size.z);
      dGeomSetBody(g, b);
      place(g, s);
      bodies_.push_back(b);
    }
    contacts_.resize(std::size_t(cfg_.max_contacts));
    poses_.resize(bodies_.size());
  }
  ~RawOdePile() {
    dJointGroupDestroy(group_);
    dSpaceDestroy(space_);
    dWorldDestroy(world_);
  }

  void step() {
    contacts_this_step = 0;
    dSpaceCollide(space_, this, &near_callback);
    dRandSetSeed(static_cast<unsigned long>(step_ * 2654435761u + 1));  // as the resolver does
    dWorldQuickStep(world_, kDt);
    dJointGroupEmpty(group_);
    // Read the poses back, as a program that draws or reports them must (the
    // harness writes them to its position and orientation columns).
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const dReal* x = dBodyGetPosition(bodies_[i]);
      const dReal* q = dBodyGetQuaternion(bodies_[i]);
      poses_[i] = {x[0], x[1], x[2], q[0], q[1], q[2], q[3]};
    }
    ++step_;
  }

 private:
  static void place(dGeomID g, const scenes::BoxSpec& s) {
    dGeomSetPosition(g, s.position.x, s.position.y, s.position.z);
    const dQuaternion q = {s.orientation.w, s.orientation.x, s.orientation.y, s.orientation.z};
    dGeomSetQuaternion(g, q);
  }
  static void near_callback(void* data, dGeomID g1, dGeomID g2) {
    auto& self = *static_cast<RawOdePile*>(data);
    dBodyID b1 = dGeomGetBody(g1), b2 = dGeomGetBody(g2);
    if (!b1 && !b2) return;
    const int n =
        dCollide(g1, g2, int(self.contacts_.size()), &self.contacts_[0].geom, sizeof(dContact));
    // Not the rigid body's motionN allowance for shallow points: with it this
    // loop ran 9 % slower in CPU time for 0.9 % more instructions (measured
    // 2026-11-21), an effect of the solver's numbers, not of work the harness
    // avoids; left out so that it cannot flatter the harness.
    for (int i = 0; i < n; ++i) {
      dContact& c = self.contacts_[std::size_t(i)];
      c.surface.mode = dContactApprox1;
      c.surface.mu = self.mu_;
      dJointID j = dJointCreateContact(self.world_, self.group_, &c);
      dJointAttach(j, b1, b2);
    }
    self.contacts_this_step += std::uint64_t(std::max(n, 0));
  }

 public:
  std::uint64_t contacts_this_step = 0;  ///< contact points made, for the work counter

 private:
  rigid::RigidBodyConfig cfg_;
  dWorldID world_;
  dSpaceID space_;
  dJointGroupID group_;
  double mu_ = 0.5;
  std::vector<dBodyID> bodies_;
  std::vector<std::array<double, 7>> poses_;  ///< position and orientation of each box
  std::vector<dContact> contacts_;
  std::uint64_t step_ = 0;
};

// --- the harness --------------------------------------------------------------------

/// Only the five plugins a rigid-body scene needs.
void register_needed(PluginRegistry& r) {
  r.add(rigid::rigid_body_plugin());
  r.add(rigid::collisions_plugin());
  r.add(rigid::rigid_body_from_collisions_plugin());
  r.add(gravity::uniform_gravity_plugin());
  r.add(rigid::rigid_body_from_gravity_plugin());
}

struct HarnessPile {
  PluginRegistry registry;
  std::unique_ptr<World> world;
  const rigid::CollisionSet* contacts = nullptr;
  rigid::ImpulseDemand impulses;  // held only by --profile-impulses

  HarnessPile(const scenes::PileLayout& layout, bool all_plugins) {
    if (all_plugins)
      register_native_plugins(registry);
    else
      register_needed(registry);
    world = std::make_unique<World>(registry, WorldDef{.dt = kDt});
    scenes::build_pile(*world, layout);
    world->start();
    contacts = &dynamic_cast<const rigid::CollisionSet&>(*world->stage("collisions"));
  }
  void step() { world->step(); }
  std::uint64_t contacts_this_step() const { return contacts->points().size(); }
};

// --- the measurement -----------------------------------------------------------------

enum { kRaw, kNeeded, kAll, kVariants };
constexpr const char* kLabel[kVariants] = {"raw ODE loop",
                                           "harness, only the needed plugins registered",
                                           "harness, every native plugin registered"};
constexpr const char* kKey[kVariants] = {"raw_ode", "harness_needed", "harness_all"};

struct Result {
  int boxes = 0, steps = 0, rounds = 0;
  double seconds[kVariants] = {};          // summed CPU seconds of the timed steps
  double contacts[kVariants] = {};         // contact points per timed step
  double ratio_needed = 0, ratio_all = 0;  // medians of the rounds' ratios
  std::size_t stages = 0, available = 0;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n == 0 ? NAN : n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

Result measure(int boxes, int settle, int rounds, int per_round, bench::Progress& progress) {
  const scenes::PileLayout layout = scenes::pile_layout(boxes);
  RawOdePile raw(layout);
  HarnessPile needed(layout, false), all(layout, true);
  for (int i = 0; i < settle; ++i) raw.step(), needed.step(), all.step();

  Result r;
  r.boxes = boxes, r.rounds = rounds, r.steps = rounds * per_round;
  r.stages = needed.world->active_stages().size();
  r.available = all.registry.order().size();
  std::vector<double> ratio_needed, ratio_all;
  std::uint64_t points[kVariants] = {};
  for (int round = 0; round < rounds; ++round) {
    double t[kVariants] = {};
    for (int k = 0; k < kVariants; ++k) {
      const int v = (round + k) % kVariants;  // rotate who goes first
      const double t0 = bench::cpu_seconds();
      for (int i = 0; i < per_round; ++i) {
        if (v == kRaw)
          raw.step();
        else
          (v == kNeeded ? needed : all).step();
      }
      t[v] = bench::cpu_seconds() - t0;
      points[v] +=
          v == kRaw ? raw.contacts_this_step : (v == kNeeded ? needed : all).contacts_this_step();
    }
    for (int v = 0; v < kVariants; ++v) r.seconds[v] += t[v];
    ratio_needed.push_back(t[kNeeded] / t[kRaw]);
    ratio_all.push_back(t[kAll] / t[kNeeded]);
    progress.tick();
  }
  for (int v = 0; v < kVariants; ++v)
    r.contacts[v] = double(points[v]) / rounds;  // sampled once a round
  r.ratio_needed = median(ratio_needed);
  r.ratio_all = median(ratio_all);
  return r;
}

int profile(int steps, bool impulses) {
  HarnessPile pile(scenes::pile_layout(1'000), false);
  if (impulses) pile.impulses = pile.contacts->demand_impulses();
  for (int i = 0; i < 240; ++i) pile.step();
  CALLGRIND_START_INSTRUMENTATION;
  for (int i = 0; i < steps; ++i) pile.step();
  CALLGRIND_STOP_INSTRUMENTATION;
  // A digest of every pose, so that a change meant to be neutral can be
  // checked bit for bit against the previous build.
  const WorldView view(*pile.world);
  const auto position = view.column<Vec3>("position");
  const auto orientation = view.column<Quat>("orientation");
  std::uint64_t digest = 1469598103934665603ull;
  auto mix = [&](double x) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    digest = (digest ^ bits) * 1099511628211ull;
  };
  for (std::uint32_t s : position.members()) {
    const Vec3 x = position[s];
    const Quat q = orientation.value_or(s, Quat{});
    for (double c : {x.x, x.y, x.z, q.w, q.x, q.y, q.z}) mix(c);
  }
  std::printf(
      "1,000-box pile: %d steps profiled after 240; %llu contact points in the last; impulses %s; pose "
      "digest %016llx\n",
      steps, (unsigned long long)pile.contacts_this_step(), pile.contacts->impulses_known() ? "computed" : "not computed",
      (unsigned long long)digest);
  return 0;
}

/// The raw ODE loop alone, the same way: the baseline's instructions per step.
int profile_raw(int steps) {
  RawOdePile raw(scenes::pile_layout(1'000));
  for (int i = 0; i < 240; ++i) raw.step();
  CALLGRIND_START_INSTRUMENTATION;
  for (int i = 0; i < steps; ++i) raw.step();
  CALLGRIND_STOP_INSTRUMENTATION;
  std::printf("1,000-box pile, raw ODE: %d steps profiled after 240; %llu contact points in the last\n",
              steps, (unsigned long long)raw.contacts_this_step);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // --profile STEPS: outside Options, which knows flags without values.
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], "--profile") == 0) return profile(std::atoi(argv[i + 1]), false);
    else if (std::strcmp(argv[i], "--profile-impulses") == 0) return profile(std::atoi(argv[i + 1]), true);
    else if (std::strcmp(argv[i], "--profile-raw") == 0) return profile_raw(std::atoi(argv[i + 1]));
  const bench::Options opt = bench::Options::parse(argc, argv, "alloy_bench_rigid");
  // Full: the 1,000-box pile, 1 s to fall, then 3 s (720 steps) timed
  // in rounds of 8. Quick: 128 boxes, a few rounds, for CI.
  const int boxes = opt.quick ? 128 : 1'000;
  const int settle = opt.quick ? 60 : 240;
  const int rounds = opt.quick ? 6 : 90;
  const int per_round = opt.quick ? 4 : 8;

  Result r;
  {
    bench::Progress progress("rigid overhead", std::size_t(rounds), opt.progress);
    r = measure(boxes, settle, rounds, per_round, progress);
  }

  const double goal_needed = 1.02, goal_all = 1.01;
  bench::Csv csv(opt.file("overhead.csv"), {"boxes", "variant", "cpu_ms_per_step",
                                            "contacts_per_step", "ratio", "ratio_of", "goal"});
  bench::Table runs({"variant", "CPU ms/step", "contact points/step"});
  for (int v = 0; v < kVariants; ++v) {
    const double ms = 1e3 * r.seconds[v] / r.steps;
    const double ratio = v == kNeeded ? r.ratio_needed : v == kAll ? r.ratio_all : 1.0;
    csv.row({bench::Csv::cell(r.boxes), kKey[v], bench::Csv::cell(ms),
             bench::Csv::cell(r.contacts[v]), bench::Csv::cell(ratio),
             v == kNeeded ? "raw_ode"
             : v == kAll  ? "harness_needed"
                          : "",
             v == kNeeded ? bench::Csv::cell(goal_needed)
             : v == kAll  ? bench::Csv::cell(goal_all)
                          : ""});
    runs.row({kLabel[v], bench::fmt(ms, 4), bench::fmt(r.contacts[v], 4)});
  }
  const double sum_needed = r.seconds[kNeeded] / r.seconds[kRaw];
  const double sum_all = r.seconds[kAll] / r.seconds[kNeeded];
  bench::Table ratios({"ratio", "median of rounds", "of the sums", "goal"});
  ratios.row(
      {"harness / raw ODE", bench::fmt(r.ratio_needed, 4), bench::fmt(sum_needed, 4), "<= 1.02"});
  ratios.row({"all plugins available / needed only", bench::fmt(r.ratio_all, 4),
              bench::fmt(sum_all, 4), "<= 1.01"});
  char head[200];
  std::snprintf(
      head, sizeof head,
      "%d boxes, %d steps of 1/240 s timed in %d rounds after %d untimed; %zu stages active, "
      "%zu plugins available in the \"all\" registry.\n\n",
      r.boxes, r.steps, r.rounds, settle, r.stages, r.available);
  const std::string md = head + runs.str() + "\n" + ratios.str();
  std::printf("\n%s", md.c_str());
  const bool met = r.ratio_needed <= goal_needed && r.ratio_all <= goal_all;
  std::printf(
      "ratio harness/raw_ode = %.4f (goal <= %.2f)\nratio all_plugins/needed_plugins = %.4f (goal "
      "<= %.2f)\n",
      r.ratio_needed, goal_needed, r.ratio_all, goal_all);
  std::printf("goals: %s\n", met ? "met" : "missed");
  if (!opt.quick) bench::splice(opt.docs, "overhead", md);
  // Quick mode checks that the program runs; 128 boxes over 24 steps are too
  // few for a 1 % goal on a shared machine.
  return met || opt.quick ? 0 : 1;
}
