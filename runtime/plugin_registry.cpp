#include "runtime/plugin_registry.hpp"

#include <algorithm>

#include "runtime/world.hpp"

namespace alloy {

PropertyId PluginContext::property(std::string_view name) const {
  return world_.properties().id(name);
}

Stage& PluginContext::stage(std::string_view name) {
  const bool declared = name == info_.target ||
                        std::find(info_.derived.begin(), info_.derived.end(), name) != info_.derived.end() ||
                        std::find(info_.resolvers.begin(), info_.resolvers.end(), name) != info_.resolvers.end();
  if (!declared)
    throw AccessError("stage '" + info_.name + "' uses '" + std::string(name) + "' without declaring it");
  Stage* s = world_.dependency_stage(info_, area_, name);
  if (!s) throw AccessError("stage '" + info_.name + "' needs '" + std::string(name) + "', which is not active");
  return *s;
}

void PluginRegistry::add(PluginDef def) {
  if (def.info.name.empty()) throw InputError("a plugin needs a name");
  if (!def.create) throw InputError("plugin '" + def.info.name + "' has no factory");
  if (def.info.kind == StageKind::Interaction && def.info.target.empty())
    throw InputError("interaction '" + def.info.name + "' must name exactly one target resolver");
  if (def.info.kind != StageKind::Resolver && !def.info.writes.empty())
    throw InputError("'" + def.info.name + "' is not a resolver and may not write properties");
  for (auto& p : def.properties) {
    if (p.owner.empty()) p.owner = def.info.name;
    properties_.add(p);
  }
  auto it = plugins_.find(def.info.name);
  if (it != plugins_.end()) {
    if (it->second.info.kind != def.info.kind)
      throw InputError("plugin '" + def.info.name + "' is already registered as a " +
                       std::string(to_string(it->second.info.kind)));
    it->second = std::move(def);
    return;
  }
  order_.push_back(def.info.name);
  std::string name = def.info.name;
  plugins_.emplace(std::move(name), std::move(def));
}

void PluginRegistry::remove(std::string_view name) {
  auto it = plugins_.find(name);
  if (it == plugins_.end()) return;
  plugins_.erase(it);
  order_.erase(std::find(order_.begin(), order_.end(), name));
}

const PluginDef* PluginRegistry::find(std::string_view name) const {
  auto it = plugins_.find(name);
  return it == plugins_.end() ? nullptr : &it->second;
}

}  // namespace alloy
