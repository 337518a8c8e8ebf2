// What the viewer asks about the rigid body's engines, by what plugins
// declare and never by their names: the world's global contact set (ODE's
// `collisions` or Box2D's `collisions.box2d`, whichever runs) and the
// engines a stage can be swapped for (rigid_body <-> rigid_body.box2d).
// Header-only and free of ImGui, so that tests can call it without a window.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "runtime/contact_set.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/world.hpp"

namespace alloy::viewer {

/// The world's global contact set: the first active stage, not scoped to an
/// area (`name@area`), whose plugin declares a contact set
/// (PluginDef::contacts), as lua/ finds it. Null if none runs.
inline ContactSet* global_contacts(World& world) {
  for (const std::string& name : world.active_stages()) {
    const PluginDef* def = world.plugin_def(name);
    if (name.find('@') == std::string::npos && def && def->contacts)
      if (auto* set = dynamic_cast<ContactSet*>(world.stage(name))) return set;
  }
  return nullptr;
}

/// The registered plugins `plugin` can be swapped for, itself included, in
/// registration order: those that provide the same thing (provided(): ODE's
/// `rigid_body` provides itself by name, Box2D's `rigid_body.box2d`
/// provides "rigid_body") and are of the same kind. Empty if there is no
/// other, or no such plugin.
inline std::vector<std::string> swap_alternatives(const PluginRegistry& registry,
                                                  std::string_view plugin) {
  const PluginDef* def = registry.find(plugin);
  std::vector<std::string> out;
  if (!def) return out;
  for (const std::string& n : registry.order())
    if (const PluginDef* d = registry.find(n);
        d && provided(*d) == provided(*def) && d->info.kind == def->info.kind)
      out.push_back(n);
  if (out.size() < 2) out.clear();
  return out;
}

}  // namespace alloy::viewer
