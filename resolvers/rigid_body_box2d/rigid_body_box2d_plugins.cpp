// Registration of the Box2D engine's plugins: `rigid_body.box2d` (provides
// rigid_body) and `collisions.box2d` (provides collisions).
#include "resolvers/rigid_body_box2d/rigid_body_box2d_plugins.hpp"

#include "resolvers/rigid_body/engine_functions.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body_box2d/box2d_engine.hpp"

namespace alloy::box2d {

namespace {
std::vector<PropertyDef> concat(std::initializer_list<std::vector<PropertyDef>> lists) {
  std::vector<PropertyDef> out;
  for (const auto& l : lists) out.insert(out.end(), l.begin(), l.end());
  return out;
}
}  // namespace

PluginDef rigid_body_box2d_plugin() {
  PluginDef def;
  def.info = {.name = "rigid_body.box2d",
              .kind = StageKind::Resolver,
              .reads = {"shape", "size", "radius", "length", "density", "static", "pinned",
                        "planar", "linear_damping", "angular_damping", "joint", "body_a", "body_b",
                        "joint_friction", "limit_low", "limit_high", "friction", "restitution"},
              .writes = {"position", "orientation", "velocity", "angular_velocity", "mass",
                         "anchor", "anchor_a", "anchor_b", "axis"},
              .needs = {"mass", "density"},
              .provides = "rigid_body",
              .doc =
                  "rigid body dynamics in the z = 0 plane (Box2D 2.4): boxes, disks, capsules, "
                  "hinges, glue, contacts with materials"};
  def.properties =
      concat({rigid::body_properties(), rigid::joint_properties(), rigid::material_properties()});
  def.check = rigid::check_object;
  // The same interaction functions as ODE's engine (the registry checks it):
  // mods and native interactions reach either engine alike.
  def.functions = rigid::engine_functions();
  def.records = rigid::engine_records();
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    return std::make_unique<Box2DEngine>(ctx.world(), Box2DConfig::from(ctx.settings()));
  };
  return def;
}

PluginDef collisions_box2d_plugin() {
  PluginDef def;
  def.info = {.name = "collisions.box2d",
              .kind = StageKind::Derived,
              .reads = {"position", "orientation", "velocity", "angular_velocity", "shape", "size",
                        "radius", "length", "static", "joint", "body_a", "body_b"},
              .resolvers = {"rigid_body.box2d"},
              .provides = "collisions",
              .doc =
                  "contact pairs of the Box2D rigid body: began, ongoing, ended, with points "
                  "and impulses"};
  def.contacts = true;  // a ContactSet: Lua stages and handlers read it
  def.properties = concat({rigid::body_properties(), rigid::joint_properties()});
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    ctx.settings().check_known("collisions.box2d", {"impulses"});
    return std::make_unique<Box2DContacts>(ctx.dependency<Box2DEngine>("rigid_body.box2d"),
                                           ctx.settings().boolean("impulses", false));
  };
  return def;
}

void register_rigid_body_box2d_plugins(PluginRegistry& registry) {
  registry.add(rigid_body_box2d_plugin());
  registry.add(collisions_box2d_plugin());
}

}  // namespace alloy::box2d
