#include "runtime/plugin_registry.hpp"

#include <algorithm>

#include "runtime/contact_set.hpp"
#include "runtime/world.hpp"

namespace alloy {

PropertyId PluginContext::property(std::string_view name) const {
  return world_.properties().id(name);
}

Stage& PluginContext::stage(std::string_view name, std::string* instance) {
  const bool declared =
      name == info_.target ||
      std::find(info_.derived.begin(), info_.derived.end(), name) != info_.derived.end() ||
      std::find(info_.resolvers.begin(), info_.resolvers.end(), name) != info_.resolvers.end();
  if (!declared)
    throw AccessError("stage '" + info_.name + "' uses '" + std::string(name) +
                      "' without declaring it");
  Stage* s = world_.dependency_stage(info_, area_, name, instance);
  if (!s)
    throw AccessError("stage '" + info_.name + "' needs '" + std::string(name) +
                      "', which is not active");
  // A contact set handed to a stage that declared it reads it makes its
  // geometry at every update (ContactSet::add_reader).
  if (auto* set = dynamic_cast<ContactSet*>(s);
      set && std::find(info_.derived.begin(), info_.derived.end(), name) != info_.derived.end())
    set->add_reader();
  return *s;
}

std::pair<Stage&, const PluginDef&> PluginContext::target_stage() {
  std::string instance;
  Stage& s = stage(info_.target, &instance);
  const PluginDef* def = world_.plugin_def(instance);
  if (!def)
    throw AccessError("stage '" + info_.name + "': the plugin of its target '" + instance +
                      "' is not registered");
  return {s, *def};
}

std::string_view to_string(ArgKind kind) {
  switch (kind) {
    case ArgKind::Number:
      return "number";
    case ArgKind::Object:
      return "object";
    case ArgKind::Vec3:
      return "vec3";
  }
  return "?";
}

std::string signature(const FunctionDecl& f) {
  std::string s = f.name + "(";
  for (std::size_t i = 0; i < f.args.size(); ++i)
    s += (i ? ", " : "") + std::string(to_string(f.args[i]));
  return s + ")";
}

namespace {

std::string signatures(const std::vector<InteractionFunction>& fns) {
  if (fns.empty()) return "none";
  std::string s;
  for (const auto& f : fns) s += (s.empty() ? "" : ", ") + signature(f.decl);
  return s;
}

// Two providers of one thing are interchangeable only if a caller bound to
// one can call the other: the same functions, in the same order (bindings
// number them), with the same arguments.
void check_same_functions(const PluginDef& def, const PluginDef& other) {
  if (declarations(def.functions) == declarations(other.functions)) return;
  throw InputError("plugin '" + def.info.name + "' provides '" + provided(def) + "' as plugin '" +
                   other.info.name + "' does, but declares other interaction functions: " +
                   signatures(def.functions) + " against '" + other.info.name + "''s " +
                   signatures(other.functions) + " (providers of one thing must declare the same)");
}

}  // namespace

void PluginRegistry::add(PluginDef def) {
  if (def.info.name.empty()) throw InputError("a plugin needs a name");
  if (!def.create) throw InputError("plugin '" + def.info.name + "' has no factory");
  if (def.info.kind == StageKind::Interaction && def.info.target.empty())
    throw InputError("interaction '" + def.info.name + "' must name exactly one target resolver");
  if (def.info.kind != StageKind::Resolver && !def.info.writes.empty())
    throw InputError("'" + def.info.name + "' is not a resolver and may not write properties");
  if (!def.functions.empty() && def.info.kind != StageKind::Resolver)
    throw InputError("'" + def.info.name +
                     "' is not a resolver and may not declare interaction functions");
  for (const auto& f : def.functions)
    if (f.record_kind >= 0 && !def.records)
      throw InputError("plugin '" + def.info.name + "': '" + f.decl.name +
                       "' has a record kind but the plugin has no record queue");
  for (const auto& [name, other] : plugins_)
    if (name != def.info.name && provided(other) == provided(def)) check_same_functions(def, other);
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
