#include "resolvers/rigid_body/rigid_body_plugins.hpp"

#include "resolvers/gravity/uniform_gravity.hpp"
#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/engine_functions.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "resolvers/rigid_body/rigid_body_from_collisions.hpp"
#include "resolvers/rigid_body/rigid_body_from_gravity.hpp"
#include "resolvers/rigid_body/rigid_body_from_springs.hpp"

namespace alloy::rigid {

namespace {
// The rigid body and the collisions set both define every body and joint
// property (either may be registered first by a partial registry).
std::vector<PropertyDef> body_and_joint_properties() {
  std::vector<PropertyDef> out = body_properties();
  for (auto& d : joint_properties()) out.push_back(std::move(d));
  return out;
}
}  // namespace

PluginDef rigid_body_plugin() {
  PluginDef def;
  def.info = {.name = "rigid_body",
              .kind = StageKind::Resolver,
              .reads = {"shape", "size", "radius", "length", "density", "static", "pinned",
                        "planar", "linear_damping", "angular_damping", "joint", "body_a", "body_b",
                        "joint_friction", "limit_low", "limit_high"},
              .writes = {"position", "orientation", "velocity", "angular_velocity", "mass",
                         "anchor", "anchor_a", "anchor_b", "axis"},
              .needs = {"mass", "density"},
              .provides = "rigid_body",
              .doc = "rigid body dynamics (ODE): bodies, hinges, glued assemblies, contacts"};
  def.properties = body_and_joint_properties();
  def.check = check_object;
  def.functions = engine_functions();
  def.records = engine_records();
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    return std::make_unique<RigidBodyResolver>(ctx.world(), RigidBodyConfig::from(ctx.settings()));
  };
  return def;
}

PluginDef collisions_plugin() {
  PluginDef def;
  def.info = {.name = "collisions",
              .kind = StageKind::Derived,
              .reads = {"position", "orientation", "velocity", "angular_velocity", "shape", "size",
                        "radius", "length", "static", "joint", "body_a", "body_b"},
              .resolvers = {"rigid_body"},
              .provides = "collisions",
              .exact = {"rigid_body"},  // ODE's collision detection, on ODE's bodies
              .doc = "contact pairs that began, continue and ended, with points and impulses"};
  def.contacts = true;  // a ContactSet: Lua stages and handlers read it
  def.properties = body_and_joint_properties();
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    ctx.settings().check_known("collisions", {"impulses"});
    auto& rigid = ctx.dependency<RigidBodyResolver>("rigid_body");
    // impulses = true: computed even if no stage demands them (for handlers of
    // contact_ended events, which cannot declare it); default: for readers only.
    return std::make_unique<CollisionSet>(rigid, rigid.config().max_contacts,
                                          ctx.settings().boolean("impulses", false));
  };
  return def;
}

PluginDef rigid_body_from_collisions_plugin() {
  PluginDef def;
  def.info = {
      .name = "rigid_body_from_collisions",
      .kind = StageKind::Interaction,
      .reads = {"friction", "restitution"},
      .derived = {"collisions"},
      .target = "rigid_body",
      // ODE's contact joints from ODE's collision set: never on another engine
      // (rigid_body.box2d mixes the same materials inside its own step).
      .exact = {"rigid_body", "collisions"},
      .doc = "contact joints for touching pairs (friction sqrt(mu_a mu_b), restitution max)"};
  def.properties = material_properties();
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    ctx.settings().check_known("rigid_body_from_collisions", {"bounce_velocity"});
    const double bounce = ctx.settings().number("bounce_velocity", 0.1);
    if (!(bounce >= 0))
      throw InputError(ctx.settings().where,
                       "rigid_body_from_collisions: bounce_velocity must be >= 0");
    return std::make_unique<RigidBodyFromCollisions>(
        ctx.target<RigidBodyResolver>(), ctx.dependency<CollisionSet>("collisions"), bounce);
  };
  return def;
}

PluginDef rigid_body_from_gravity_plugin() {
  PluginDef def;
  def.info = {.name = "rigid_body_from_gravity",
              .kind = StageKind::Interaction,
              .reads = {"gravity", "mass"},
              .target = "rigid_body",
              .doc = "the force m g on every body with a gravity value"};
  def.properties = {gravity::gravity_property()};
  def.properties.push_back(body_property("mass"));
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    ctx.settings().check_known("rigid_body_from_gravity", {});
    return std::make_unique<RigidBodyFromGravity>(ctx.target<RigidBodyEngine>());
  };
  return def;
}

void register_rigid_body_plugins(PluginRegistry& registry) {
  registry.add(rigid_body_plugin());
  registry.add(collisions_plugin());
  registry.add(rigid_body_from_collisions_plugin());
  register_rigid_body_from_springs(registry);
}

}  // namespace alloy::rigid
