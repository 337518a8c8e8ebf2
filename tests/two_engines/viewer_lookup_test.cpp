// The viewer's lookups of the rigid body's engines (apps/viewer/engines.hpp):
// the global contact set is found by what its plugin declares, so a world on
// Box2D shows its contacts, and the swap list of ODE's rigid_body offers
// rigid_body.box2d (and back). Before, the viewer asked for the stage named
// "collisions" and skipped plugins that provide nothing by name (ODE's).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "apps/viewer/engines.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/world.hpp"

namespace alloy::viewer {
namespace {

/// A ball dropped on a floor, on `engine`'s plugins ("box2d" or ODE's).
struct Drop {
  explicit Drop(bool box2d) {
    register_native_plugins(registry);
    WorldDef def;
    if (box2d) def.use = {{"rigid_body", "rigid_body.box2d"}, {"collisions", "collisions.box2d"}};
    world = std::make_unique<World>(registry, def);
    const ObjectId floor = world->create("floor");
    world->set(floor, "shape", std::string("box"));
    world->set(floor, "size", Vec3{2, 0.2, 0.2});
    world->set(floor, "position", Vec3{0, -0.1, 0});
    world->set(floor, "static", true);
    const ObjectId ball = world->create("ball");
    world->set(ball, "shape", std::string("sphere"));
    world->set(ball, "radius", 0.05);
    world->set(ball, "mass", 0.1);
    world->set(ball, "position", Vec3{0, 0.06, 0});
    world->run(60);  // resting on the floor
  }
  PluginRegistry registry;
  std::unique_ptr<World> world;
};

std::string stage_name_of(World& w, const Stage* s) {
  for (const std::string& n : w.active_stages())
    if (w.stage(n) == s) return n;
  return "";
}

TEST(ViewerEngines, TheContactSetIsFoundOnEitherEngine) {
  for (const bool box2d : {false, true}) {
    Drop d(box2d);
    ContactSet* set = global_contacts(*d.world);
    ASSERT_NE(set, nullptr) << (box2d ? "Box2D" : "ODE");
    EXPECT_EQ(stage_name_of(*d.world, set), box2d ? "collisions.box2d" : "collisions");
    EXPECT_EQ(set->began().size() + set->ongoing().size(), 1u) << "the ball on the floor";
  }
}

TEST(ViewerEngines, TheSwapListOffersTheOtherEngine) {
  PluginRegistry registry;
  register_native_plugins(registry);
  auto has = [](const std::vector<std::string>& v, const char* n) {
    return std::find(v.begin(), v.end(), n) != v.end();
  };
  const auto rigid = swap_alternatives(registry, "rigid_body");
  EXPECT_TRUE(has(rigid, "rigid_body")) << rigid.size();
  EXPECT_TRUE(has(rigid, "rigid_body.box2d"));
  EXPECT_EQ(swap_alternatives(registry, "rigid_body.box2d"), rigid);
  const auto contacts = swap_alternatives(registry, "collisions");
  EXPECT_TRUE(has(contacts, "collisions.box2d"));
  EXPECT_FALSE(has(contacts, "rigid_body.box2d"));                  // another kind of plugin
  EXPECT_TRUE(swap_alternatives(registry, "electricity").empty());  // nothing else provides it
  EXPECT_TRUE(swap_alternatives(registry, "no_such_plugin").empty());
}

}  // namespace
}  // namespace alloy::viewer
