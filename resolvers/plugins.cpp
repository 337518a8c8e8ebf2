#include "resolvers/plugins.hpp"

#include "resolvers/electricity/electricity_from_collisions.hpp"
#include "resolvers/gravity/nbody_gravity.hpp"
#include "resolvers/gravity/uniform_gravity.hpp"
#include "resolvers/light/light_interactions.hpp"
#include "resolvers/magnetism/electricity_from_magnetism.hpp"
#include "resolvers/magnetism/magnetism_plugins.hpp"
#include "resolvers/magnetism/rigid_body_from_magnetism.hpp"
#include "resolvers/rigid_body/collisions.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body/rigid_body.hpp"
#include "resolvers/rigid_body/rigid_body_from_collisions.hpp"
#include "resolvers/rigid_body/rigid_body_from_gravity.hpp"
#include "resolvers/rigid_body_box2d/box2d_plugins.hpp"
#include "resolvers/sound/sound_plugins.hpp"

namespace alloy {

namespace {
std::vector<PropertyDef> concat(std::initializer_list<std::vector<PropertyDef>> lists) {
  std::vector<PropertyDef> out;
  for (const auto& l : lists) out.insert(out.end(), l.begin(), l.end());
  return out;
}
std::vector<PropertyDef> pick(const std::vector<PropertyDef>& defs,
                              std::initializer_list<const char*> names) {
  std::vector<PropertyDef> out;
  for (const char* n : names)
    for (const auto& d : defs)
      if (d.name == n) out.push_back(d);
  return out;
}
}  // namespace

namespace rigid {

PluginDef rigid_body_plugin() {
  PluginDef def;
  def.info = {.name = "rigid_body",
              .kind = StageKind::Resolver,
              .reads = {"shape", "size", "radius", "length", "density", "static", "pinned",
                        "planar", "linear_damping", "angular_damping", "joint", "body_a", "body_b",
                        "joint_friction", "limit_low", "limit_high"},
              .writes = {"position", "orientation", "velocity", "angular_velocity", "mass",
                         "anchor", "axis"},
              .needs = {"mass", "density"},
              .provides = "rigid_body",
              .doc = "rigid body dynamics (ODE): bodies, hinges, glued assemblies, contacts"};
  def.properties = concat({body_properties(), joint_properties()});
  def.check = check_object;
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
  def.properties = concat({body_properties(), joint_properties()});
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
  def.properties = concat({{gravity::gravity_property()}, pick(body_properties(), {"mass"})});
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    ctx.settings().check_known("rigid_body_from_gravity", {});
    return std::make_unique<RigidBodyFromGravity>(ctx.target<RigidBodyEngine>());
  };
  return def;
}

}  // namespace rigid

namespace gravity {

PluginDef uniform_gravity_plugin() {
  PluginDef def;
  def.info = {.name = "gravity.uniform",
              .kind = StageKind::Resolver,
              .reads = {"mass", "density", "static"},
              .writes = {"gravity"},
              .needs = {"mass", "density"},
              .provides = "gravity",
              .doc = "uniform gravitational acceleration g (setting g, default {0,-9.81,0})"};
  def.properties =
      concat({{gravity_property()}, pick(rigid::body_properties(), {"mass", "density", "static"})});
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    ctx.settings().check_known("gravity.uniform", {"g"});
    const Vec3 g = ctx.settings().vec3("g", {0, -9.81, 0});
    if (!is_finite(g)) throw InputError(ctx.settings().where, "gravity.uniform: g must be finite");
    return std::make_unique<UniformGravity>(g);
  };
  return def;
}

PluginDef nbody_gravity_plugin() {
  PluginDef def;
  def.info = {.name = "gravity.nbody",
              .kind = StageKind::Resolver,
              .reads = {"position", "mass", "density", "static"},
              .writes = {"gravity"},
              .needs = {"mass", "density"},
              .provides = "gravity",
              .doc =
                  "Newtonian gravity of every mass on the bodies in scope (settings G, default SI; "
                  "softening, m; "
                  "sources = \"world\" or \"area\")"};
  def.properties =
      concat({{gravity_property()},
              pick(rigid::body_properties(), {"position", "mass", "density", "static"})});
  def.create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
    const PluginSettings& s = ctx.settings();
    s.check_known("gravity.nbody", {"G", "softening", "sources"});
    const double G = s.number("G", kGravitationalConstant);
    const double eps = s.number("softening", 0.0);
    const std::string sources = s.string("sources", "world");
    if (sources != "world" && sources != "area")
      throw InputError(s.where,
                       "gravity.nbody: sources must be \"world\" (every mass attracts) or \"area\" "
                       "(only the masses in the area), got \"" +
                           sources + "\"");
    if (!(G >= 0) || !std::isfinite(G))
      throw InputError(s.where, "gravity.nbody: G must be a finite number >= 0");
    if (!(eps >= 0) || !std::isfinite(eps))
      throw InputError(s.where, "gravity.nbody: softening must be a finite number of metres >= 0");
    return std::make_unique<NBodyGravity>(G, eps, sources == "area");
  };
  return def;
}

}  // namespace gravity

void register_native_plugins(PluginRegistry& registry) {
  registry.add(rigid::rigid_body_plugin());
  registry.add(rigid::collisions_plugin());
  registry.add(rigid::rigid_body_from_collisions_plugin());
  registry.add(gravity::uniform_gravity_plugin());
  registry.add(gravity::nbody_gravity_plugin());
  registry.add(rigid::rigid_body_from_gravity_plugin());
  electricity::register_electricity_plugins(registry);
  magnetism::register_magnetism_plugins(registry);
  magnetism::register_rigid_body_from_magnetism(registry);
  magnetism::register_electricity_from_magnetism(registry);
  sound::register_sound_plugins(registry);
  light::register_light_plugins(registry);
  box2d::register_rigid_body_box2d_plugins(registry);
}

}  // namespace alloy
