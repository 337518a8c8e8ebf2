#include "tests/lua/scene_plugins.hpp"

#ifdef ALLOY_TEST_NATIVE_PLUGINS
#include "resolvers/plugins.hpp"
#else
#include "runtime/world.hpp"
#endif

namespace alloy::test {

#ifdef ALLOY_TEST_NATIVE_PLUGINS

void register_scene_plugins(PluginRegistry& registry) { register_native_plugins(registry); }

#else

namespace {

struct NullResolver : Resolver {
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess&, double) override {}
};
struct NullDerived : DerivedSet {
  void update(const WorldView&) override {}
};
struct NullInteraction : Interaction {
  void apply(const WorldView&) override {}
};

PropertyDef number(const char* name, std::optional<double> min = {}) {
  return {.name = name, .kind = PropertyKind::Number, .min = min};
}
PropertyDef vec3(const char* name) { return {.name = name, .kind = PropertyKind::Vec3}; }
PropertyDef boolean(const char* name) { return {.name = name, .kind = PropertyKind::Bool}; }

std::vector<PropertyDef> contract_properties() {
  return {
      vec3("position"), {.name = "orientation", .kind = PropertyKind::Quat}, vec3("velocity"),
      vec3("angular_velocity"), number("mass", 0.0), number("density", 0.0),
      {.name = "shape", .kind = PropertyKind::Enum, .enum_values = {"box", "sphere", "capsule"}},
      vec3("size"), number("radius", 0.0), number("length", 0.0), boolean("static"), boolean("pinned"),
      boolean("planar"), number("friction", 0.0), number("restitution", 0.0), number("linear_damping", 0.0),
      number("angular_damping", 0.0),
      {.name = "joint", .kind = PropertyKind::Enum, .enum_values = {"hinge", "fixed"}},
      {.name = "body_a", .kind = PropertyKind::Ref}, {.name = "body_b", .kind = PropertyKind::Ref},
      vec3("anchor"), vec3("axis"), number("joint_friction", 0.0), number("limit_low"), number("limit_high"),
  };
}

}  // namespace

void register_scene_plugins(PluginRegistry& registry) {
  registry.add({.info = {.name = "rigid_body", .kind = StageKind::Resolver, .needs = {"shape"}},
                .properties = contract_properties(),
                .create = [](PluginContext&) { return std::make_unique<NullResolver>(); }});
  registry.add({.info = {.name = "gravity.uniform", .kind = StageKind::Resolver, .needs = {"mass"}},
                .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
                  ctx.settings().check_known("gravity.uniform", {"g"});
                  return std::make_unique<NullResolver>();
                }});
  registry.add({.info = {.name = "collisions", .kind = StageKind::Derived, .resolvers = {"rigid_body"}},
                .create = [](PluginContext&) { return std::make_unique<NullDerived>(); }});
  registry.add({.info = {.name = "rigid_body_from_gravity", .kind = StageKind::Interaction,
                         .resolvers = {"gravity.uniform"}, .target = "rigid_body"},
                .create = [](PluginContext&) { return std::make_unique<NullInteraction>(); }});
  registry.add({.info = {.name = "rigid_body_from_collisions", .kind = StageKind::Interaction,
                         .derived = {"collisions"}, .target = "rigid_body"},
                .create = [](PluginContext&) { return std::make_unique<NullInteraction>(); }});
}

#endif

}  // namespace alloy::test
