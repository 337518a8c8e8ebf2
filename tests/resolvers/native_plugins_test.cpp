// register_native_plugins (resolvers/plugins.cpp, the physics list of
// resolvers/CMakeLists.txt): the registration order is the order stages run in
// when nothing else decides, and the golden hashes hash the stage order, so a
// physics folder that registers its plugins elsewhere in the list, or an
// interaction registered by the wrong folder, must show here by name.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "resolvers/plugins.hpp"

namespace alloy {
namespace {

TEST(NativePlugins, RegisterFolderByFolderInTheOrderStagesRunIn) {
  PluginRegistry registry;
  register_native_plugins(registry);
  const std::vector<std::string> expected = {
      // rigid_body/
      "rigid_body", "collisions", "rigid_body_from_collisions", "rigid_body_from_springs",
      // gravity/, then rigid_body_from_gravity (lives in rigid_body/, registers with gravity)
      "gravity.uniform", "gravity.nbody", "rigid_body_from_gravity",
      // electricity/
      "electricity", "electricity_from_collisions",
      // magnetism/, then the interactions it joins to the rigid body and electricity
      "magnetism", "magnetic_forces", "magnetism_from_electricity", "rigid_body_from_magnetism",
      "electricity_from_magnetism",
      // sound/
      "sound", "sound_from_collisions",
      // light/
      "light", "illuminance", "light_from_electricity", "electricity_from_light",
      // rigid_body_box2d/: a second provider of rigid_body and collisions
      "rigid_body.box2d", "collisions.box2d"};
  EXPECT_EQ(registry.order(), expected);
}

TEST(NativePlugins, EveryInteractionIsRegisteredAfterTheStagesItJoins) {
  PluginRegistry registry;
  register_native_plugins(registry);
  const auto& order = registry.order();
  auto rank = [&](const std::string& name) {
    return std::size_t(std::find(order.begin(), order.end(), name) - order.begin());
  };
  for (const std::string& name : order) {
    const PluginDef* def = registry.find(name);
    ASSERT_NE(def, nullptr) << name;
    if (def->info.kind != StageKind::Interaction) continue;
    ASSERT_LT(rank(def->info.target), order.size()) << name << ": target not registered";
    EXPECT_LT(rank(def->info.target), rank(name)) << name << " before its target";
    for (const auto& d : def->info.derived) {
      ASSERT_LT(rank(d), order.size()) << name << ": set " << d << " not registered";
      EXPECT_LT(rank(d), rank(name)) << name << " before the set " << d;
    }
  }
}

}  // namespace
}  // namespace alloy
