// Plugins by name: every resolver, derived set and interaction the runtime can
// create. Native plugins register from resolvers/ (explicitly, no static-init
// tricks); Lua mods register through lua/. A world instantiates only the
// plugins its objects need.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "runtime/interaction_function.hpp"
#include "runtime/stage.hpp"

namespace alloy {

class World;
struct PluginDef;

/// What a factory gets: the world, its settings, and typed access to the
/// stages it depends on (the target of an interaction, the derived sets read).
class PluginContext {
 public:
  PluginContext(World& world, const StageInfo& info, const PluginSettings& settings,
                std::string area = "")
      : world_(world), info_(info), settings_(settings), area_(std::move(area)) {}
  /// The area the stage is created for, or "" for a global stage.
  const std::string& area() const { return area_; }

  World& world() { return world_; }
  const StageInfo& info() const { return info_; }
  const PluginSettings& settings() const { return settings_; }
  PropertyId property(std::string_view name) const;

  /// The interaction's target resolver, as its concrete type.
  template <class T>
  T& target() {
    return cast<T>(stage(info_.target), info_.target);
  }
  /// The interaction's target resolver as a stage, with the definition of
  /// the plugin that made it (the provider active for this stage's area):
  /// the interaction functions to call it with. Throws AccessError.
  std::pair<Stage&, const PluginDef&> target_stage();
  /// A derived set or resolver this stage declared it reads, as its concrete type.
  template <class T>
  T& dependency(std::string_view name) {
    return cast<T>(stage(name), name);
  }

 private:
  Stage& stage(std::string_view name, std::string* instance = nullptr);
  template <class T>
  static T& cast(Stage& s, std::string_view name) {
    if (T* t = dynamic_cast<T*>(&s)) return *t;
    throw AccessError("stage '" + std::string(name) + "' is not of the expected type");
  }
  World& world_;
  const StageInfo& info_;
  const PluginSettings& settings_;
  std::string area_;
};

struct PluginDef {
  StageInfo info;
  /// Property types this plugin defines (registered with the plugin).
  std::vector<PropertyDef> properties;
  std::function<std::unique_ptr<Stage>(PluginContext&)> create;
  /// Optional whole-object check: throws InputError when an object, taken as
  /// a whole, is not something this plugin can simulate (a box without a
  /// size, a joint to itself). Run by World::check on scene load and edits.
  std::function<void(const World&, ObjectId)> check;
  /// A resolver's interaction functions: what interactions (native ones, and
  /// Lua mods' through lua/'s generic binding) may call on it, in this order.
  /// Plugins that provide the same thing declare the same signatures.
  std::vector<InteractionFunction> functions;
  /// The resolver's in-place queue for the functions with a record_kind.
  RecordQueue records;
  /// A derived set whose stage is a ContactSet (runtime/contact_set.hpp):
  /// Lua stages may read it (`w:contacts`) and handlers its contact events.
  bool contacts = false;
};

/// What a plugin stands for when alternatives are compared: its `provides`,
/// or its own name if it provides nothing named (`rigid_body` is what the
/// ODE plugin of that name provides, and a second engine provides it too).
inline const std::string& provided(const PluginDef& def) {
  return def.info.provides.empty() ? def.info.name : def.info.provides;
}

class PluginRegistry {
 public:
  /// Registers a plugin and its property types. A second plugin of the same
  /// name replaces the first (hot reload); its kind must match. A plugin
  /// that provides what another registered plugin provides (provided())
  /// must declare the same interaction functions: InputError naming both if
  /// not, and nothing is registered.
  void add(PluginDef def);
  /// Removes a plugin by name (mod unload). Its property types stay: objects
  /// may still carry them.
  void remove(std::string_view name);
  const PluginDef* find(std::string_view name) const;
  /// In registration order: the order stages run in when nothing else decides.
  const std::vector<std::string>& order() const { return order_; }
  PropertyRegistry& properties() { return properties_; }
  const PropertyRegistry& properties() const { return properties_; }

 private:
  PropertyRegistry properties_;
  std::map<std::string, PluginDef, std::less<>> plugins_;
  std::vector<std::string> order_;
};

}  // namespace alloy
