// Overhead of the harness on a rigid-body scene, as ratios measured in one run:
//
//   harness / raw ODE        the world stepping a 500-box pile (rigid_body,
//                            collisions, the two interactions, gravity) against
//                            a loop written by hand over ODE with the same
//                            scene, solver, iterations, contact parameters,
//                            space type and step. Goal: <= 1.05.
//   all plugins / needed     the same scene in a registry with every native
//                            plugin (electricity, magnetism, ... unneeded here)
//                            against one holding only the five it needs.
//                            Goal: <= 1.02.
//
// Each repetition builds the pile, lets it fall for 1 s (untimed), then times
// 240 steps (1 s) of the pile landing and settling; repetitions of the
// variants are interleaved at random; each ratio is of the median CPU time
// per step (the ratio of the best is printed beside it).
#include <benchmark/benchmark.h>
#include <ode/ode.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "resolvers/plugins.hpp"
#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace {

using namespace alloy;

constexpr int kBoxes = 500;
constexpr int kSettleSteps = 240;
constexpr int kTimedSteps = 240;
constexpr double kDt = 1.0 / 240.0;
constexpr double kG = 9.81;

// --- the baseline: ODE by hand ------------------------------------------------------

/// What a programmer writes with ODE alone: bodies with geoms, a hash space,
/// a near callback making contact joints, QuickStep, empty the group.
class RawOdePile {
 public:
  explicit RawOdePile(const scenes::PileLayout& layout) : cfg_() {
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
  }
  ~RawOdePile() {
    dJointGroupDestroy(group_);
    dSpaceDestroy(space_);
    dWorldDestroy(world_);
  }

  void step() {
    dSpaceCollide(space_, this, &near_callback);
    dRandSetSeed(static_cast<unsigned long>(step_ * 2654435761u + 1));  // as the resolver does
    dWorldQuickStep(world_, kDt);
    dJointGroupEmpty(group_);
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
    const int n = dCollide(g1, g2, int(self.contacts_.size()), &self.contacts_[0].geom, sizeof(dContact));
    for (int i = 0; i < n; ++i) {
      dContact& c = self.contacts_[std::size_t(i)];
      c.surface.mode = dContactApprox1;
      c.surface.mu = self.mu_;
      dJointID j = dJointCreateContact(self.world_, self.group_, &c);
      dJointAttach(j, b1, b2);
    }
    self.contacts += std::uint64_t(std::max(n, 0));
  }

 public:
  std::uint64_t contacts = 0;  ///< contact points made, for the work counter

 private:

  rigid::RigidBodyConfig cfg_;
  dWorldID world_;
  dSpaceID space_;
  dJointGroupID group_;
  double mu_ = 0.5;
  std::vector<dBodyID> bodies_;
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

const scenes::PileLayout& layout() {
  static const scenes::PileLayout l = scenes::pile_layout(kBoxes);
  return l;
}

void BM_RawOde(benchmark::State& state) {
  RawOdePile pile(layout());
  for (int i = 0; i < kSettleSteps; ++i) pile.step();
  const std::uint64_t before = pile.contacts;
  for (auto _ : state) pile.step();
  state.counters["contacts"] = double(pile.contacts - before) / double(state.iterations());
}

template <bool kAllPlugins>
void BM_Harness(benchmark::State& state) {
  PluginRegistry registry;
  if (kAllPlugins) register_native_plugins(registry);
  else register_needed(registry);
  World world(registry);
  scenes::build_pile(world, layout());
  world.run(kSettleSteps);
  const auto& contacts = dynamic_cast<const rigid::CollisionSet&>(*world.stage("collisions"));
  std::uint64_t points = 0;
  for (auto _ : state) {
    world.step();
    points += contacts.points().size();
  }
  state.counters["contacts"] = double(points) / double(state.iterations());
  state.counters["stages"] = double(world.active_stages().size());
  state.counters["available"] = double(registry.order().size());
}

void BM_HarnessAllPlugins(benchmark::State& state) { BM_Harness<true>(state); }
void BM_HarnessNeededPlugins(benchmark::State& state) { BM_Harness<false>(state); }

#define PILE_BENCH(fn) \
  BENCHMARK(fn)->Unit(benchmark::kMillisecond)->Iterations(kTimedSteps)->Repetitions(9)->ReportAggregatesOnly(false)
PILE_BENCH(BM_RawOde);
PILE_BENCH(BM_HarnessNeededPlugins);
PILE_BENCH(BM_HarnessAllPlugins);

/// Keeps every repetition's time per step, by benchmark.
class Collector : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, std::vector<double>> cpu, wall;  // seconds per step
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs)
      if (r.run_type == Run::RT_Iteration && r.iterations > 0) {
        cpu[r.run_name.function_name].push_back(r.cpu_accumulated_time / double(r.iterations));
        wall[r.run_name.function_name].push_back(r.real_accumulated_time / double(r.iterations));
      }
    ConsoleReporter::ReportRuns(runs);
  }
};

double lowest(const std::vector<double>& v) { return v.empty() ? 0 : *std::min_element(v.begin(), v.end()); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n == 0 ? 0 : n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

}  // namespace

int main(int argc, char** argv) {
  // Interleave the variants' repetitions so that a slow moment of the machine
  // falls on all of them alike.
  std::vector<char*> args(argv, argv + argc);
  std::string interleave = "--benchmark_enable_random_interleaving=true";
  args.insert(args.begin() + 1, interleave.data());
  int n = int(args.size());
  benchmark::Initialize(&n, args.data());
  Collector collector;
  benchmark::RunSpecifiedBenchmarks(&collector);
  benchmark::Shutdown();

  // The ratios use CPU time: the step is single-threaded, and on a shared
  // machine wall time also counts the other processes' turns. The median of
  // the interleaved repetitions is the estimate (measured here it moves less
  // between runs than the best); the best is printed beside it.
  struct Row {
    const char* label;
    const char* name;
  };
  const Row rows[] = {{"raw ODE loop", "BM_RawOde"},
                      {"harness, needed only", "BM_HarnessNeededPlugins"},
                      {"harness, all plugins", "BM_HarnessAllPlugins"}};
  std::printf("\n%d-box pile, %d steps of 1/240 s after %d untimed; CPU ms/step, median and best of %zu:\n",
              kBoxes, kTimedSteps, kSettleSteps, collector.cpu["BM_RawOde"].size());
  for (const Row& r : rows)
    std::printf("  %-22s %.3f  %.3f\n", r.label, 1e3 * median(collector.cpu[r.name]), 1e3 * lowest(collector.cpu[r.name]));
  auto ratio = [&](const char* what, const char* num, const char* den, double goal) {
    const double best = lowest(collector.cpu[num]) / lowest(collector.cpu[den]);
    const double med = median(collector.cpu[num]) / median(collector.cpu[den]);
    std::printf("ratio %s = %.3f (best %.3f; goal <= %.2f)\n", what, med, best, goal);
  };
  ratio("harness/raw_ode", "BM_HarnessNeededPlugins", "BM_RawOde", 1.05);
  ratio("all_plugins/needed_plugins", "BM_HarnessAllPlugins", "BM_HarnessNeededPlugins", 1.02);
  return 0;
}
