// An object without a position (a joint, a spring, a wire) is scoped by the
// positioned objects its Ref and RefList properties name (World::split_areas):
// in their area when they share one, split (in no area and in no stage that
// differs between their areas) when they do not. With plain test stages: no
// rigid body, nothing about joints.
#include <gtest/gtest.h>

#include <algorithm>

#include "runtime/world.hpp"

namespace alloy {
namespace {

/// Notes, at each build and advance, which links (objects with `link_to` or
/// `link_list`) are in its scope.
class Linker : public Resolver {
 public:
  void build(ResolverAccess& a) override { look(a); }
  void advance(ResolverAccess& a, double) override { look(a); }
  bool sees(ObjectId id) const {
    return std::find(seen.begin(), seen.end(), id.index) != seen.end();
  }
  std::vector<std::uint32_t> seen;

 private:
  void look(ResolverAccess& a) {
    seen.clear();
    for (std::uint32_t s : a.column<ObjectId>("link_to").members()) seen.push_back(s);
    for (std::uint32_t s : a.column<RefList>("link_list").members())
      if (std::find(seen.begin(), seen.end(), s) == seen.end()) seen.push_back(s);
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

PluginDef linker(const std::string& name, std::string provides) {
  return {.info = {.name = name,
                   .kind = StageKind::Resolver,
                   .reads = {"link_to", "link_list"},
                   .needs = {"link_to"},
                   .provides = std::move(provides)},
          .create = [](PluginContext&) { return std::make_unique<Linker>(); }};
}

class AreaReferences : public ::testing::Test {
 protected:
  AreaReferences() {
    registry.properties().add({.name = "position", .kind = PropertyKind::Vec3});
    registry.properties().add({.name = "link_to", .kind = PropertyKind::Ref});
    registry.properties().add({.name = "link_list", .kind = PropertyKind::RefList});
    registry.add(linker("link.one", "link"));
    registry.add(linker("link.two", "link"));
    registry.add(linker("watch", ""));  // global, never replaced in an area
    registry.add({.info = {.name = "mover",
                           .kind = StageKind::Resolver,
                           .writes = {"position"},
                           .needs = {"position"}},
                  .create = [](PluginContext&) { return std::make_unique<Mover>(); }});
  }
  /// Area "left": x < 0 (within 5 m), with its own provider of "link".
  WorldDef def(double dt = 0.25) {
    WorldDef d;
    d.dt = dt;
    d.plugins = {"link.one", "watch", "mover"};
    d.areas.push_back(AreaDef{
        .name = "left", .center = {-5, 0, 0}, .half_extents = {5, 5, 5}, .plugins = {"link.two"}});
    return d;
  }
  ObjectId at(World& w, const std::string& name, double x) {
    const ObjectId id = w.create(name);
    w.set(id, "position", Vec3{x, 0, 0});
    return id;
  }
  Linker& stage(World& w, const char* name) { return dynamic_cast<Linker&>(*w.stage(name)); }
  PluginRegistry registry;
};

TEST_F(AreaReferences, ALinkGoesWhereItsReferentsAreAndIsSplitWhenTheyDisagree) {
  World w(registry, def());
  const ObjectId p = at(w, "p", -3), q = at(w, "q", -2), r = at(w, "r", 3);
  const ObjectId inside = w.create("inside"), across = w.create("across"),
                 listed = w.create("listed"), nowhere = w.create("nowhere");
  w.set(inside, "link_to", q);
  w.set(across, "link_to", r);
  w.set(across, "link_list", RefList{p});                 // RefLists count too
  w.set(listed, "link_list", RefList{p, q, ObjectId{}});  // a null entry names nothing
  w.set(nowhere, "link_to", ObjectId{});
  std::vector<std::string> split_told;
  w.add_observer([&](const Event& e) {
    if (e.type == "area_split") split_told.push_back(w.store().describe(e.a) + ": " + e.text);
  });
  w.run(2);
  EXPECT_EQ(w.area_of(inside), "left");
  EXPECT_EQ(w.area_of(listed), "left");
  EXPECT_EQ(w.area_of(nowhere), "");
  EXPECT_EQ(w.area_of(across), "");
  EXPECT_EQ(w.split_areas(across), (std::vector<std::string>{"", "left"}));
  EXPECT_TRUE(w.split_areas(inside).empty());
  EXPECT_EQ(split_told, (std::vector<std::string>{"across: (no area), left"}));
  Linker &one = stage(w, "link.one"), &two = stage(w, "link.two@left"), &watch = stage(w, "watch");
  EXPECT_TRUE(two.sees(inside) && two.sees(listed));
  EXPECT_FALSE(one.sees(inside) || one.sees(listed));
  EXPECT_TRUE(one.sees(nowhere));
  // Split: neither provider of "link" acts on it; a stage the area does not
  // replace still does (it acts on both referents).
  EXPECT_FALSE(one.sees(across));
  EXPECT_FALSE(two.sees(across));
  EXPECT_TRUE(watch.sees(across));
}

TEST_F(AreaReferences, ALinkFollowsItsReferentsAcrossABorderSplittingOnTheWay) {
  // p and q move right at 1 m/s from -0.85 and -0.35: q crosses first, the
  // link is split until p crosses too, then it is the global provider's.
  World w(registry, def(0.25));
  const ObjectId p = at(w, "p", -0.85), q = at(w, "q", -0.35);
  const ObjectId link = w.create("link");
  w.set(link, "link_to", p);
  w.set(link, "link_list", RefList{q});
  std::vector<std::string> told;
  w.add_observer([&](const Event& e) {
    if (e.a == link) told.push_back(e.type + " " + e.text);
  });
  std::vector<std::string> where;
  for (int i = 0; i < 4; ++i) {
    w.step();
    const auto split = w.split_areas(link);
    where.push_back(split.empty() ? w.area_of(link) : "split");
  }
  EXPECT_EQ(where, (std::vector<std::string>{"left", "split", "split", ""}));
  EXPECT_EQ(told, (std::vector<std::string>{"area_entered (no area) -> left",
                                            "area_split (no area), left",
                                            "area_entered (split) -> (no area)"}));
  EXPECT_TRUE(stage(w, "link.one").sees(link));
  EXPECT_FALSE(stage(w, "link.two@left").sees(link));
}

TEST_F(AreaReferences, ARestoreComesBackWithTheSameSplits) {
  auto build = [&](World& w) {
    const ObjectId p = at(w, "p", -0.85), q = at(w, "q", -0.35);
    const ObjectId link = w.create("link");
    w.set(link, "link_to", p);
    w.set(link, "link_list", RefList{q});
    // Keeps link.two@left needed (a restore makes only the stages the
    // restored objects need, and the split link needs none in "left").
    w.set(w.create("stays"), "link_to", at(w, "r", -4.5));
    return link;
  };
  World w(registry, def(0.25));
  const ObjectId link = build(w);
  w.run(2);
  ASSERT_EQ(w.split_areas(link).size(), 2u);
  const Snapshot split = w.snapshot();
  w.run(2);
  ASSERT_TRUE(w.split_areas(link).empty());
  w.restore(split);
  EXPECT_EQ(w.split_areas(link), (std::vector<std::string>{"", "left"}));
  w.step();
  EXPECT_FALSE(stage(w, "link.one").sees(link));
  EXPECT_FALSE(stage(w, "link.two@left").sees(link));
  World fresh(registry, def(0.25));
  build(fresh);
  fresh.restore(split);
  EXPECT_EQ(fresh.split_areas(link), (std::vector<std::string>{"", "left"}));
}

}  // namespace
}  // namespace alloy
