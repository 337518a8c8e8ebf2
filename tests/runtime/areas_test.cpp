// Tests for areas and resolver swaps (runtime/world.hpp, runtime/scope.hpp):
// stages of an area act only on the objects in it, a provider in an area
// replaces the global one there, objects crossing a border keep every
// property, and a resolver swapped while running rebuilds from properties.
#include <gtest/gtest.h>

#include "runtime/world.hpp"

namespace alloy {
namespace {

/// Writes its own number into `tag` for every object with a position in scope.
class Tagger : public Resolver {
 public:
  explicit Tagger(double value) : value_(value) {}
  void build(ResolverAccess& a) override {
    ++builds;
    tag(a);
  }
  void advance(ResolverAccess& a, double) override { tag(a); }
  void on_scope_exit(ResolverAccess& a, std::span<const std::uint32_t> left) override {
    auto t = a.writer<double>("tag");
    for (std::uint32_t s : left) exited.push_back(s), (void)t;
  }
  int builds = 0;
  std::vector<std::uint32_t> exited;

 private:
  void tag(ResolverAccess& a) {
    auto t = a.writer<double>("tag");
    for (std::uint32_t s : a.column<Vec3>("position").members()) t.set(s, value_);
  }
  double value_;
};

/// Tries to write an object outside its area.
class Trespasser : public Resolver {
 public:
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess& a, double) override { a.writer<double>("tag").set(target, 9.0); }
  std::uint32_t target = 0;
};

/// Writes `tag` for its area's objects and erases it for those that leave.
class Eraser : public Resolver {
 public:
  void build(ResolverAccess& a) override {
    auto t = a.writer<double>("tag");
    for (std::uint32_t s : a.column<Vec3>("position").members()) t.set(s, 7.0);
  }
  void advance(ResolverAccess&, double) override {}
  void on_scope_exit(ResolverAccess& a, std::span<const std::uint32_t> left) override {
    auto t = a.writer<double>("tag");
    for (std::uint32_t s : left) t.erase(s);
  }
};

/// Moves every object with a position along +x at 1 m/s.
class Mover : public Resolver {
 public:
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess& a, double dt) override {
    auto x = a.writer<Vec3>("position");
    for (std::uint32_t s : x.members()) x.set(s, x[s] + Vec3{dt, 0, 0});
  }
};

/// Counts, per advance, the pokes queued on it since its last advance.
class Counter : public Resolver {
 public:
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess&, double) override {
    per_advance.push_back(pokes);
    pokes = 0;
  }
  void poke() { ++pokes; }
  int pokes = 0;
  std::vector<int> per_advance;
};

/// Pokes its counter once a step.
class Poker : public Interaction {
 public:
  explicit Poker(Counter& c) : counter_(c) {}
  void apply(const WorldView&) override { counter_.poke(); }

 private:
  Counter& counter_;
};

PluginDef tagger(const std::string& name, double value) {
  return {.info = {.name = name,
                   .kind = StageKind::Resolver,
                   .reads = {"position"},
                   .writes = {"tag"},
                   .needs = {"position"},
                   .provides = "tag"},
          .create = [value](PluginContext&) { return std::make_unique<Tagger>(value); }};
}

class AreasTest : public ::testing::Test {
 protected:
  AreasTest() {
    registry.properties().add({.name = "position", .kind = PropertyKind::Vec3});
    registry.properties().add({.name = "tag", .kind = PropertyKind::Number});
    registry.properties().add({.name = "mass", .kind = PropertyKind::Number});
    registry.add(tagger("tag.one", 1));
    registry.add(tagger("tag.two", 2));
    registry.add(tagger("tag.three", 3));
  }
  WorldDef def_with_left_area() {
    WorldDef def;
    def.areas.push_back(AreaDef{
        .name = "left", .center = {-5, 0, 0}, .half_extents = {5, 5, 5}, .plugins = {"tag.two"}});
    return def;
  }
  ObjectId body(World& w, const std::string& name, double x) {
    ObjectId id = w.create(name);
    w.set(id, "position", Vec3{x, 0, 0});
    w.set(id, "mass", 1.0);
    return id;
  }
  double tag(World& w, ObjectId id) { return std::get<double>(w.get(id, "tag")); }
  PluginRegistry registry;
};

TEST_F(AreasTest, OneProviderPerScopeAndAreasReplaceTheGlobalOne) {
  World w(registry, def_with_left_area());
  const ObjectId a = body(w, "a", -3), b = body(w, "b", 3);
  w.step();
  EXPECT_EQ(w.area_of(a), "left");
  EXPECT_EQ(w.area_of(b), "");
  EXPECT_TRUE(w.has_stage("tag.one"));
  EXPECT_TRUE(w.has_stage("tag.two@left"));
  EXPECT_FALSE(w.has_stage("tag.three"));  // another provider of "tag": not chosen
  EXPECT_FALSE(w.has_stage("tag.two"));
  EXPECT_EQ(tag(w, a), 2);
  EXPECT_EQ(tag(w, b), 1);
}

TEST_F(AreasTest, AnObjectCrossingABorderKeepsItsPropertiesAndChangesResolver) {
  World w(registry, def_with_left_area());
  const ObjectId a = body(w, "a", -3);
  body(w, "b", 3);
  w.run(3);
  auto& left = dynamic_cast<Tagger&>(*w.stage("tag.two@left"));
  std::vector<Event> crossings;
  w.add_observer([&](const Event& e) {
    if (e.type == "area_entered") crossings.push_back(e);
  });
  w.set(a, "position", Vec3{4, 0, 0});  // carried across the border
  w.step();
  ASSERT_EQ(crossings.size(), 1u);
  EXPECT_EQ(crossings[0].a, a);
  EXPECT_EQ(crossings[0].text, "left -> (no area)");
  EXPECT_EQ(w.area_of(a), "");
  EXPECT_EQ(tag(w, a), 1);                             // the global provider took it over
  EXPECT_EQ(std::get<double>(w.get(a, "mass")), 1.0);  // every property kept
  EXPECT_EQ(left.exited, (std::vector<std::uint32_t>{a.index}));
  w.set(a, "position", Vec3{-1, 0, 0});
  w.step();
  EXPECT_EQ(tag(w, a), 2);
}

TEST_F(AreasTest, AResolverErasesWhatItWroteForObjectsThatLeftBeforeTheNewProviderWrites) {
  // tag.two (registered before tag.erase) takes the object over in "right": its
  // build must come after tag.erase's exit, or the object would be left untagged.
  registry.add({.info = {.name = "tag.erase",
                         .kind = StageKind::Resolver,
                         .reads = {"position"},
                         .writes = {"tag"},
                         .needs = {"position"},
                         .provides = "tag"},
                .create = [](PluginContext&) { return std::make_unique<Eraser>(); }});
  registry.add(
      {.info = {.name = "idle", .kind = StageKind::Resolver, .needs = {"nothing carries this"}},
       .create = [](PluginContext&) { return std::make_unique<Eraser>(); }});
  WorldDef def;
  def.plugins = {"idle"};  // no global provider: outside the areas nothing writes tag
  def.areas.push_back(AreaDef{
      .name = "left", .center = {-5, 0, 0}, .half_extents = {5, 5, 5}, .plugins = {"tag.erase"}});
  def.areas.push_back(AreaDef{
      .name = "right", .center = {5, 0, 0}, .half_extents = {5, 5, 5}, .plugins = {"tag.two"}});
  World w(registry, def);
  const ObjectId a = body(w, "a", -3), b = body(w, "b", -2);
  w.step();
  EXPECT_EQ(tag(w, a), 7);
  w.set(a, "position", Vec3{3, 0, 0});   // into "right"
  w.set(b, "position", Vec3{30, 0, 0});  // out of every area
  w.step();
  EXPECT_EQ(w.area_of(a), "right");
  EXPECT_EQ(tag(w, a), 2);
  EXPECT_EQ(w.area_of(b), "");
  EXPECT_THROW(w.get(b, "tag"), AccessError);  // erased: no stale value
  EXPECT_EQ(std::get<double>(w.get(b, "mass")), 1.0);
}

TEST_F(AreasTest, ABodyMovedAcrossABorderIsHandedOverInTheStepItCrossed) {
  registry.add({.info = {.name = "mover",
                         .kind = StageKind::Resolver,
                         .writes = {"position"},
                         .needs = {"position"}},
                .create = [](PluginContext&) { return std::make_unique<Mover>(); }});
  WorldDef def;
  def.dt = 0.25;
  def.areas.push_back(AreaDef{
      .name = "right", .center = {5, 0, 0}, .half_extents = {5, 5, 5}, .plugins = {"tag.two"}});
  World w(registry, def);
  const ObjectId a = body(w, "a", -0.625);
  w.step();  // to -0.375
  EXPECT_EQ(w.area_of(a), "");
  EXPECT_EQ(tag(w, a), 1);
  w.run(2);  // to -0.125, then 0.125: inside "right" at the end of this step
  EXPECT_EQ(std::get<Vec3>(w.get(a, "position")).x, 0.125);
  EXPECT_EQ(w.area_of(a), "right");
  EXPECT_EQ(tag(w, a), 2);  // what the interactions of this step read
}

TEST_F(AreasTest, AnInteractionCreatedWhenABodyCrossesQueuesOncePerStep) {
  // The counter and its poker exist in "right" only once a body is there. The
  // body crosses during an advance: the new poker must queue once for the
  // next advance, not once when it is created and again in the same step.
  registry.add({.info = {.name = "mover",
                         .kind = StageKind::Resolver,
                         .writes = {"position"},
                         .needs = {"position"}},
                .create = [](PluginContext&) { return std::make_unique<Mover>(); }});
  registry.add({.info = {.name = "counter", .kind = StageKind::Resolver, .needs = {"position"}},
                .create = [](PluginContext&) { return std::make_unique<Counter>(); }});
  registry.add(
      {.info = {.name = "poker",
                .kind = StageKind::Interaction,
                .needs = {"position"},
                .target = "counter"},
       .create = [](PluginContext& c) { return std::make_unique<Poker>(c.target<Counter>()); }});
  WorldDef def;
  def.dt = 0.25;
  def.plugins = {"mover"};  // globally; the counter and poker only in "right"
  def.areas.push_back(AreaDef{.name = "right",
                              .center = {5, 0, 0},
                              .half_extents = {5, 5, 5},
                              .plugins = {"counter", "poker"}});
  World w(registry, def);
  body(w, "a", -0.375);
  w.run(6);  // crosses in the second step's advance
  auto* counter = dynamic_cast<Counter*>(w.stage("counter@right"));
  ASSERT_NE(counter, nullptr);
  ASSERT_FALSE(counter->per_advance.empty());
  for (int n : counter->per_advance) EXPECT_EQ(n, 1);
}

TEST_F(AreasTest, ScopedViewsListOnlyTheAreasObjects) {
  World w(registry, def_with_left_area());
  body(w, "a", -3);
  body(w, "b", 3);
  body(w, "c", -8);
  w.step();
  const Scope* left = w.view().scope();
  EXPECT_EQ(left, nullptr);  // the world's own view sees everything
  // The area's stage wrote only its two objects.
  EXPECT_EQ(tag(w, w.find("c")), 2);
  EXPECT_EQ(tag(w, w.find("b")), 1);
}

TEST_F(AreasTest, AResolverOfAnAreaCannotWriteOutsideIt) {
  registry.add({.info = {.name = "trespasser",
                         .kind = StageKind::Resolver,
                         .writes = {"tag"},
                         .needs = {"position"}},
                .create = [](PluginContext&) { return std::make_unique<Trespasser>(); }});
  WorldDef def;
  def.areas.push_back(AreaDef{
      .name = "left", .center = {-5, 0, 0}, .half_extents = {5, 5, 5}, .plugins = {"trespasser"}});
  def.plugins = {"trespasser"};
  World w(registry, def);
  body(w, "inside", -3);
  const ObjectId outside = body(w, "outside", 3);
  w.start();
  dynamic_cast<Trespasser&>(*w.stage("trespasser@left")).target = outside.index;
  EXPECT_THROW(w.step(), AccessError);
}

TEST_F(AreasTest, SwappingAResolverWhileRunningKeepsEveryProperty) {
  World w(registry, def_with_left_area());
  const ObjectId a = body(w, "a", -3), b = body(w, "b", 3);
  w.run(2);
  const Vec3 pa = std::get<Vec3>(w.get(a, "position"));
  w.swap("", "tag.one", "tag.three");  // globally
  EXPECT_FALSE(w.has_stage("tag.one"));
  EXPECT_TRUE(w.has_stage("tag.three"));
  EXPECT_EQ(tag(w, b), 3);  // built from the properties at once
  EXPECT_EQ(tag(w, a), 2);  // the area keeps its own provider
  w.swap("left", "tag.two", "tag.one");
  EXPECT_TRUE(w.has_stage("tag.one@left"));
  EXPECT_EQ(tag(w, a), 1);
  EXPECT_EQ(std::get<Vec3>(w.get(a, "position")), pa);
  w.step();
  EXPECT_EQ(tag(w, a), 1);
  EXPECT_EQ(tag(w, b), 3);
  EXPECT_THROW(w.swap("left", "tag.two", "tag.one"), InputError);  // no longer there
  EXPECT_THROW(w.swap("", "tag.one", "tag.nine"), InputError);
  EXPECT_THROW(w.swap("nowhere", "tag.one", "tag.two"), InputError);
}

TEST_F(AreasTest, ScheduledSwapHappensAtItsTime) {
  World w(registry, def_with_left_area());
  const ObjectId b = body(w, "b", 3);
  w.schedule_swap(5 * w.dt(), "", "tag.one", "tag.three");
  std::vector<Event> swaps;
  w.add_observer([&](const Event& e) {
    if (e.type == "resolver_swapped") swaps.push_back(e);
  });
  w.run(5);
  EXPECT_EQ(tag(w, b), 1);
  w.step();
  EXPECT_EQ(tag(w, b), 3);
  ASSERT_EQ(swaps.size(), 1u);
  EXPECT_EQ(swaps[0].text, "tag.one -> tag.three (everywhere)");
  EXPECT_EQ(swaps[0].step, 6u);
}

TEST_F(AreasTest, BadAreasAreRefused) {
  WorldDef def;
  def.areas.push_back(AreaDef{.name = "x", .plugins = {"tag.nope"}});
  EXPECT_THROW(World(registry, def), InputError);
  WorldDef twice;
  twice.areas = {AreaDef{.name = "x"}, AreaDef{.name = "x"}};
  EXPECT_THROW(World(registry, twice), InputError);
  EXPECT_THROW(World(registry, WorldDef{.use = {{"tag", "nothing"}}}), InputError);
  // Two providers of one thing in one area would both act on its objects.
  WorldDef both;
  both.areas = {AreaDef{.name = "x", .plugins = {"tag.two", "tag.three"}}};
  EXPECT_THROW(World(registry, both), InputError);
}

TEST_F(AreasTest, ASwapReplacesAProviderOnlyByAnotherOfTheSameThing) {
  // An adversary swapped gravity for the Box2D engine: both rigid-body
  // engines then moved every body (at twice its speed), and the swap was
  // reported as done. A swap must stay within one thing, from the one running.
  registry.properties().add({.name = "colour", .kind = PropertyKind::Number});
  registry.add({.info = {.name = "paint",
                         .kind = StageKind::Resolver,
                         .reads = {"position"},
                         .writes = {"colour"},
                         .needs = {"position"},
                         .provides = "colour"},
                .create = [](PluginContext&) { return std::make_unique<Counter>(); }});
  World w(registry, def_with_left_area());
  body(w, "b", 3);
  w.run(1);
  try {
    w.swap("", "tag.one", "paint");
    ADD_FAILURE() << "a swap across two things was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'tag.one' provides 'tag' and 'paint' provides 'colour'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(w.has_stage("tag.one"));
  // tag.three does not run globally (tag.one does): nothing to swap out; a
  // swap to the one running is nothing at all.
  EXPECT_THROW(w.swap("", "tag.three", "tag.two"), InputError);
  w.swap("", "tag.two", "tag.one");
  EXPECT_TRUE(w.has_stage("tag.one"));
  EXPECT_TRUE(w.has_stage("tag.one"));
  EXPECT_FALSE(w.has_stage("tag.two"));
  w.swap("", "tag.one", "tag.three");  // within one thing: done
  EXPECT_TRUE(w.has_stage("tag.three"));
}

TEST_F(AreasTest, AWorldWithoutAreasPaysNothingForThem) {
  World w(registry);
  const ObjectId b = body(w, "b", 3);
  w.run(3);
  EXPECT_EQ(w.area_of(b), "");
  EXPECT_EQ(tag(w, b), 1);
}

}  // namespace
}  // namespace alloy
