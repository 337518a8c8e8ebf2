#include "resolvers/gravity/gravity_plugins.hpp"

#include <cmath>
#include <string>

#include "resolvers/gravity/nbody_gravity.hpp"
#include "resolvers/gravity/uniform_gravity.hpp"
#include "resolvers/rigid_body/properties.hpp"
#include "resolvers/rigid_body/rigid_body_plugins.hpp"

namespace alloy::gravity {

PluginDef uniform_gravity_plugin() {
  PluginDef def;
  def.info = {.name = "gravity.uniform",
              .kind = StageKind::Resolver,
              .reads = {"mass", "density", "static"},
              .writes = {"gravity"},
              .needs = {"mass", "density"},
              .provides = "gravity",
              .doc = "uniform gravitational acceleration g (setting g, default {0,-9.81,0})"};
  def.properties = {gravity_property()};
  for (const char* name : {"mass", "density", "static"})
    def.properties.push_back(rigid::body_property(name));
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
  def.properties = {gravity_property()};
  for (const char* name : {"position", "mass", "density", "static"})
    def.properties.push_back(rigid::body_property(name));
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

void register_gravity_plugins(PluginRegistry& registry) {
  registry.add(uniform_gravity_plugin());
  registry.add(nbody_gravity_plugin());
  registry.add(rigid::rigid_body_from_gravity_plugin());
}

}  // namespace alloy::gravity
