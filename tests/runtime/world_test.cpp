// Tests for runtime/world.hpp: the order of the step, the one-step delay of
// interaction commands, skipping of unneeded plugins and unchanged derived
// sets, `every = n`, declared writes, and determinism. The plugins here are
// small but real stages written against the public contracts.
#include "runtime/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace alloy {
namespace {

std::vector<std::string> g_log;  // phase calls, in order

/// A resolver that integrates a 1D oscillator per object (x, v) and performs
/// queued "kick" commands (velocity changes) at the start of its advance.
class Oscillator : public Resolver {
 public:
  struct Kick {
    std::uint32_t slot;
    double dv;
    std::uint64_t queued_at;
  };
  void kick(std::uint32_t slot, double dv, std::uint64_t step) {
    queue_.push_back({slot, dv, step});
  }

  void build(ResolverAccess& a) override { ++builds; }
  void advance(ResolverAccess& a, double dt) override {
    g_log.push_back("advance:oscillator");
    dts.push_back(dt);
    auto x = a.writer<double>("x");
    auto v = a.writer<double>("v");
    for (const Kick& k : queue_) {
      performed.push_back({k.queued_at, a.step()});
      v.set(k.slot, v[k.slot] + k.dv);
    }
    queue_.clear();
    for (std::uint32_t s : x.members()) {  // semi-implicit Euler, k = 1
      v.set(s, v[s] - x[s] * dt);
      x.set(s, x[s] + v[s] * dt);
    }
  }
  int builds = 0;
  std::vector<double> dts;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> performed;  // (queued at, performed at)

 private:
  std::vector<Kick> queue_;
};

/// A derived set: the total energy of all oscillators.
class Energy : public DerivedSet {
 public:
  void update(const WorldView& w) override {
    g_log.push_back("update:energy");
    auto x = w.column<double>("x");
    auto v = w.column<double>("v");
    total = 0;
    for (std::uint32_t s : x.members())
      total += 0.5 * (x[s] * x[s] + v.value_or(s, 0) * v.value_or(s, 0));
    ++updates;
  }
  bool on_demand() const override { return demand; }
  double total = 0;
  int updates = 0;
  bool demand = false;
};

/// An interaction: kicks every oscillator whose energy derived set is below a threshold.
class Kicker : public Interaction {
 public:
  Kicker(Oscillator& target, Energy& energy) : target_(target), energy_(energy) {}
  void apply(const WorldView& w) override {
    g_log.push_back("apply:kicker");
    if (energy_.total < threshold)
      for (std::uint32_t s : w.column<double>("x").members()) target_.kick(s, 1.0, w.step());
  }
  double threshold = 0;

 private:
  Oscillator& target_;
  Energy& energy_;
};

/// A resolver that tries to write a column it did not declare.
class Rogue : public Resolver {
 public:
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess& a, double) override { a.writer<double>("x"); }
};

int g_created_magnets = 0;
class Magnets : public Resolver {
 public:
  Magnets() { ++g_created_magnets; }
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess&, double) override { g_log.push_back("advance:magnets"); }
};

void register_test_plugins(PluginRegistry& r) {
  r.add({.info = {.name = "oscillator",
                  .kind = StageKind::Resolver,
                  .reads = {"x", "v"},
                  .writes = {"x", "v"},
                  .needs = {"x"}},
         .properties = {{.name = "x", .kind = PropertyKind::Number, .unit = "m"},
                        {.name = "v", .kind = PropertyKind::Number, .unit = "m/s"}},
         .create = [](PluginContext&) { return std::make_unique<Oscillator>(); }});
  r.add(
      {.info = {.name = "energy", .kind = StageKind::Derived, .reads = {"x", "v"}, .needs = {"x"}},
       .create = [](PluginContext&) { return std::make_unique<Energy>(); }});
  r.add({.info = {.name = "kicker",
                  .kind = StageKind::Interaction,
                  .derived = {"energy"},
                  .target = "oscillator"},
         .create = [](PluginContext& c) {
           auto k =
               std::make_unique<Kicker>(c.target<Oscillator>(), c.dependency<Energy>("energy"));
           k->threshold = c.settings().number("threshold", 0);
           return k;
         }});
  r.add({.info = {.name = "magnets", .kind = StageKind::Resolver, .needs = {"pole"}},
         .properties = {{.name = "pole", .kind = PropertyKind::Number}},
         .create = [](PluginContext&) { return std::make_unique<Magnets>(); }});
}

class WorldTest : public ::testing::Test {
 protected:
  void SetUp() override {
    g_log.clear();
    g_created_magnets = 0;
    register_test_plugins(registry);
  }
  ObjectId add_oscillator(World& w, const std::string& name, double x) {
    ObjectId id = w.create(name);
    w.set(id, "x", x);
    w.set(id, "v", 0.0);
    return id;
  }
  PluginRegistry registry;
};

TEST_F(WorldTest, StepRunsAdvanceThenDeriveThenInteract) {
  World w(registry);
  add_oscillator(w, "a", 1.0);
  w.start();
  EXPECT_EQ(g_log, (std::vector<std::string>{"update:energy", "apply:kicker"}));  // priming
  g_log.clear();
  w.step();
  w.step();
  EXPECT_EQ(g_log,
            (std::vector<std::string>{"advance:oscillator", "update:energy", "apply:kicker",
                                      "advance:oscillator", "update:energy", "apply:kicker"}));
  EXPECT_EQ(w.active_stages(), (std::vector<std::string>{"oscillator", "energy", "kicker"}));
}

TEST_F(WorldTest, CommandsArePerformedInTheNextAdvance) {
  World w(registry);
  const ObjectId a = add_oscillator(w, "a", 1.0);
  w.start();
  auto& kicker = dynamic_cast<Kicker&>(*w.stage("kicker"));
  auto& osc = dynamic_cast<Oscillator&>(*w.stage("oscillator"));
  kicker.threshold = 10;  // kick on every interact from now on
  const double v_before = std::get<double>(w.get(a, "v"));
  w.step();  // performs nothing: the priming interact ran with threshold 0
  EXPECT_TRUE(osc.performed.empty());
  EXPECT_LT(std::get<double>(w.get(a, "v")), v_before + 0.5);  // no kick applied yet
  w.step();  // performs the kick queued by step 0's interact
  ASSERT_EQ(osc.performed.size(), 1u);
  EXPECT_EQ(osc.performed[0].second, osc.performed[0].first + 1);
  EXPECT_GT(std::get<double>(w.get(a, "v")), v_before + 0.5);
}

TEST_F(WorldTest, PluginsWhoseInputsNoObjectCarriesAreNotInstantiated) {
  World w(registry);
  add_oscillator(w, "a", 1.0);
  w.run(5);
  EXPECT_EQ(g_created_magnets, 0);
  EXPECT_FALSE(w.has_stage("magnets"));
  EXPECT_EQ(w.profile().not_instantiated, (std::vector<std::string>{"magnets"}));
  for (const auto& line : g_log) EXPECT_NE(line, "advance:magnets");
  // A magnet dropped into the running world brings its resolver to life.
  const ObjectId m = w.create("magnet");
  w.set(m, "pole", 1.0);
  w.step();
  EXPECT_EQ(g_created_magnets, 1);
  EXPECT_TRUE(w.has_stage("magnets"));
}

TEST_F(WorldTest, AnEmptyWorldInstantiatesNothing) {
  World w(registry);
  w.run(3);
  EXPECT_TRUE(w.active_stages().empty());
  EXPECT_EQ(w.profile().not_instantiated.size(), 4u);
}

TEST_F(WorldTest, DerivedSetIsNotRecomputedWhenItsInputsAreUnchanged) {
  World w(registry);
  add_oscillator(w, "a", 0.0);  // at rest at equilibrium: the oscillator writes no change
  w.run(10);
  auto& energy = dynamic_cast<Energy&>(*w.stage("energy"));
  EXPECT_EQ(energy.updates, 1);  // the priming update only
  const auto& timing = w.profile().stages[1];
  EXPECT_EQ(timing.name, "energy");
  EXPECT_EQ(timing.skipped, 10u);
  // An edit from outside is a change: the set recomputes once, then rests again.
  w.set(w.find("a"), "v", 0.5);
  w.step();
  EXPECT_EQ(energy.updates, 2);
}

TEST_F(WorldTest, EveryNRunsAStageEveryNthStepWithNTimesTheStep) {
  WorldDef def;
  def.every["oscillator"] = 3;
  World w(registry, def);
  add_oscillator(w, "a", 1.0);
  w.run(9);
  auto& osc = dynamic_cast<Oscillator&>(*w.stage("oscillator"));
  ASSERT_EQ(osc.dts.size(), 3u);
  for (double dt : osc.dts) EXPECT_DOUBLE_EQ(dt, 3 * def.dt);
  EXPECT_EQ(w.profile().stages[0].skipped, 6u);
  EXPECT_THROW(World(registry, WorldDef{.every = {{"oscillator", 0}}}), InputError);
}

TEST_F(WorldTest, StagesAreTimedOnlyWhenAsked) {
  // A scene pays nothing for a profile nobody reads: the counts are kept, the
  // clock is read only with timing on (alloy run --profile, the viewer).
  World w(registry);
  add_oscillator(w, "a", 1.0);
  EXPECT_FALSE(w.timing());
  w.run(20);
  EXPECT_EQ(w.profile().steps, 20u);
  EXPECT_EQ(w.profile().stages[0].runs, 20u);
  EXPECT_EQ(w.profile().stages[0].seconds, 0.0);
  EXPECT_EQ(w.profile().phases.total(), 0.0);
  w.set_timing(true);
  w.run(20);
  EXPECT_EQ(w.profile().stages[0].runs, 40u);
  EXPECT_GT(w.profile().phases.total(), 0.0);
}

TEST_F(WorldTest, AnInteractionQueuesOnlyForTheAdvanceOfATargetThatRunsEveryNthStep) {
  // The kicker kicks every step; the oscillator advances every 3rd. Each
  // advance must perform one kick per object, queued just before it, not the
  // three queued since its last advance.
  WorldDef def;
  def.every["oscillator"] = 3;
  World w(registry, def);
  add_oscillator(w, "a", 1.0);
  w.start();
  dynamic_cast<Kicker&>(*w.stage("kicker")).threshold = 1e9;  // always kick
  w.run(9);
  auto& osc = dynamic_cast<Oscillator&>(*w.stage("oscillator"));
  ASSERT_EQ(osc.dts.size(), 3u);
  std::vector<std::pair<std::uint64_t, std::uint64_t>> queued_performed;
  for (const auto& p : osc.performed) queued_performed.push_back(p);
  // Priming queues at step 0 for the advance of step 0 (threshold 0 then: no
  // kick); afterwards the kicker runs at steps 2 and 5, for steps 3 and 6.
  EXPECT_EQ(queued_performed,
            (std::vector<std::pair<std::uint64_t, std::uint64_t>>{{2, 3}, {5, 6}}));
}

TEST_F(WorldTest, AnOnDemandDerivedSetIsRecomputedOnlyWhenAReaderRuns) {
  // The oscillator moves every step, so the energy's inputs always change;
  // its one reader, the kicker, runs every 3rd step.
  auto updates = [&](bool demand, std::vector<std::string> plugins) {
    WorldDef def;
    def.every["kicker"] = 3;
    def.plugins = std::move(plugins);
    World w(registry, def);
    add_oscillator(w, "a", 1.0);
    w.start();  // primes the energy: one update
    auto& energy = dynamic_cast<Energy&>(*w.stage("energy"));
    energy.demand = demand;
    g_log.clear();
    w.run(9);
    // Each update the kicker reads is made in its own step, just before it.
    for (std::size_t i = 0; i < g_log.size(); ++i) {
      if (g_log[i] == "apply:kicker") {
        EXPECT_EQ(g_log.at(i - 1), "update:energy");
      }
    }
    return energy.updates;
  };
  EXPECT_EQ(updates(false, {}), 1 + 9);  // priming, then every step
  EXPECT_EQ(updates(true, {}), 1 + 3);   // priming, then steps 0, 3, 6
  // Read by no stage: a tool may read it, every step.
  EXPECT_EQ(updates(true, {"oscillator", "energy"}), 1 + 9);
}

TEST_F(WorldTest, HeldStagesAreReportedOnce) {
  // `every` on a derived set read by a stage that runs more often, or on an
  // interaction whose target runs more often: the reader sees a held output,
  // the target advances without commands in between (the motor ran away with
  // magnetic_forces every 2nd step: docs/performance.md "Session 21"). Told
  // once per pair, as a "held_stage" event from the world.
  auto held = [&](std::map<std::string, int, std::less<>> every) {
    WorldDef def;
    def.every = std::move(every);
    World w(registry, def);
    add_oscillator(w, "a", 1.0);
    std::vector<std::string> texts;
    auto collect = [&] {
      for (const Event& e : w.events())
        if (e.type == "held_stage") texts.push_back(e.text);
    };
    w.start();  // the stages are made here: told with start's events
    collect();
    for (int k = 0; k < 6; ++k) w.step(), collect();
    return texts;
  };
  EXPECT_TRUE(held({}).empty());
  EXPECT_TRUE(held({{"oscillator", 3}}).empty());  // a resolver's output held: multi-rate
  // All three at one rate: nothing is held.
  EXPECT_TRUE(held({{"energy", 2}, {"kicker", 2}, {"oscillator", 2}}).empty());
  const auto energy = held({{"energy", 2}});
  ASSERT_EQ(energy.size(), 1u);
  EXPECT_NE(energy[0].find("kicker reads energy, which runs every 2 steps"), std::string::npos)
      << energy[0];
  const auto kicker = held({{"kicker", 3}});
  ASSERT_EQ(kicker.size(), 1u);
  EXPECT_NE(kicker[0].find("oscillator is commanded by kicker, which runs every 3 steps"),
            std::string::npos)
      << kicker[0];
}

TEST_F(WorldTest, AResolverCannotWriteAColumnItDidNotDeclare) {
  registry.add({.info = {.name = "rogue", .kind = StageKind::Resolver, .needs = {"x"}},
                .create = [](PluginContext&) { return std::make_unique<Rogue>(); }});
  World w(registry, WorldDef{.plugins = {"rogue"}});
  add_oscillator(w, "a", 1.0);
  try {
    w.step();
    FAIL() << "an undeclared write went through";
  } catch (const AccessError& e) {
    EXPECT_NE(std::string(e.what()).find("resolver 'rogue' may not write 'x'"), std::string::npos);
  }
}

TEST_F(WorldTest, OnlyResolversMayDeclareWrites) {
  EXPECT_THROW(registry.add({.info = {.name = "bad", .kind = StageKind::Derived, .writes = {"x"}},
                             .create = [](PluginContext&) { return std::make_unique<Energy>(); }}),
               InputError);
  EXPECT_THROW(registry.add({.info = {.name = "bad2", .kind = StageKind::Interaction},
                             .create = [](PluginContext&) { return std::make_unique<Energy>(); }}),
               InputError);  // an interaction without a target
}

TEST_F(WorldTest, SameSceneAndInputsGiveBitIdenticalResults) {
  auto run = [&] {
    World w(registry);
    for (int i = 0; i < 5; ++i) add_oscillator(w, "o" + std::to_string(i), 0.1 * i);
    w.start();
    dynamic_cast<Kicker&>(*w.stage("kicker")).threshold = 0.05;
    w.run(500);
    std::vector<double> out;
    for (int i = 0; i < 5; ++i) {
      out.push_back(std::get<double>(w.get(w.find("o" + std::to_string(i)), "x")));
      out.push_back(std::get<double>(w.get(w.find("o" + std::to_string(i)), "v")));
    }
    return out;
  };
  const auto a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(std::memcmp(&a[i], &b[i], sizeof(double)), 0);
}

TEST_F(WorldTest, EventsArePublishedAfterTheStepWithStepAndTime) {
  class Emitter : public Resolver {
   public:
    void build(ResolverAccess&) override {}
    void advance(ResolverAccess& a, double) override {
      if (a.step() == 2) a.emit({.type = "ding", .values = {{"pitch", 880.0}}});
    }
  };
  registry.add({.info = {.name = "emitter", .kind = StageKind::Resolver, .needs = {"x"}},
                .create = [](PluginContext&) { return std::make_unique<Emitter>(); }});
  World w(registry);
  add_oscillator(w, "a", 1.0);
  std::vector<Event> seen;
  w.add_observer([&](const Event& e) { seen.push_back(e); });
  w.run(4);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].type, "ding");
  EXPECT_EQ(seen[0].source, "emitter");
  EXPECT_EQ(seen[0].step, 3u);  // emitted in the third step's advance (when 2 steps were done)
  EXPECT_DOUBLE_EQ(seen[0].time, 3 * w.dt());
  EXPECT_DOUBLE_EQ(seen[0].value("pitch"), 880.0);
  EXPECT_TRUE(w.events().empty());  // the last step had none
}

TEST_F(WorldTest, StructuralChangesRebuildResolvers) {
  World w(registry);
  add_oscillator(w, "a", 1.0);
  w.step();
  auto& osc = dynamic_cast<Oscillator&>(*w.stage("oscillator"));
  const int builds = osc.builds;
  w.step();
  EXPECT_EQ(osc.builds, builds);  // nothing changed
  add_oscillator(w, "b", 1.0);
  w.step();
  EXPECT_EQ(osc.builds, builds + 1);
}

TEST_F(WorldTest, ScheduledInputsApplyBetweenStepsAtTheirTime) {
  World w(registry);
  const ObjectId a = add_oscillator(w, "a", 0.0);
  w.schedule(10 * w.dt(), a, registry.properties().id("v"), 2.0);
  EXPECT_THROW(w.schedule(1.0, a, registry.properties().id("v"), Vec3{}),
               InputError);  // checked now
  EXPECT_EQ(w.pending_inputs(), 1u);
  std::vector<Event> inputs;
  w.add_observer([&](const Event& e) {
    if (e.type == "input") inputs.push_back(e);
  });
  w.run(10);
  EXPECT_EQ(std::get<double>(w.get(a, "x")), 0.0);  // at rest until the input
  w.step();                                         // the step that starts at t = 10 dt
  EXPECT_GT(std::get<double>(w.get(a, "x")), 0.0);
  ASSERT_EQ(inputs.size(), 1u);
  EXPECT_EQ(inputs[0].step, 11u);
  EXPECT_EQ(inputs[0].a, a);
  EXPECT_EQ(inputs[0].text, "v = 2");
  EXPECT_EQ(w.pending_inputs(), 0u);
}

TEST_F(WorldTest, StagesCreatedMidRunArePrimedLikeAtStart) {
  WorldDef def;
  def.settings["kicker"].set("threshold", 10.0);  // kick whenever it applies
  World w(registry, def);
  const ObjectId m = w.create("magnet");
  w.set(m, "pole", 1.0);
  w.run(3);
  EXPECT_FALSE(w.has_stage("oscillator"));
  add_oscillator(w, "late", 1.0);
  w.step();  // creates oscillator, energy and kicker, primes them, then advances
  auto& osc = dynamic_cast<Oscillator&>(*w.stage("oscillator"));
  ASSERT_EQ(osc.performed.size(), 1u) << "the kick queued at creation acts in the same step";
  EXPECT_EQ(dynamic_cast<Energy&>(*w.stage("energy")).updates, 2);  // primed, then this step's
}

}  // namespace
}  // namespace alloy
