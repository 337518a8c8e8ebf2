#include "lua/scene_builder.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>


namespace alloy::lua {

namespace {

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

[[noreturn]] void wrong_type(const PropertyDef& def, const std::string& expected,
                             const SceneValue& got) {
  throw InputError("'" + def.name + "' expects " + expected + ", got " + describe(got));
}

const std::vector<double>* numbers(const SceneValue& v) {
  return std::get_if<std::vector<double>>(&v);
}

/// {x, y} (z = 0, the play area) or {x, y, z}.
std::optional<Vec3> vec3_of(const SceneValue& v) {
  const auto* n = numbers(v);
  if (!n || (n->size() != 2 && n->size() != 3)) return std::nullopt;
  return Vec3{(*n)[0], (*n)[1], n->size() == 3 ? (*n)[2] : 0.0};
}

std::string plugin_hint(const PluginRegistry& registry, const std::string& name) {
  std::string near = closest_name(name, registry.order());
  return near.empty() ? "" : " (did you mean '" + near + "'?)";
}

PropertyValue setting_value(const SceneValue& v, const std::string& plugin,
                            const std::string& key) {
  if (const double* d = std::get_if<double>(&v)) return *d;
  if (const bool* b = std::get_if<bool>(&v)) return *b;
  if (const std::string* s = std::get_if<std::string>(&v)) return *s;
  if (auto vec = vec3_of(v)) return *vec;
  throw InputError("world: setting '" + key + "' of '" + plugin +
                   "' must be a number, a boolean, a string or "
                   "a vector {x, y[, z]}, not " +
                   describe(v));
}

/// One plugin's settings as written in world{} or in an area; `what` starts
/// the messages ("world", "world: area 'moon'").
PluginSettings make_settings(const RecordedSettings& s, const std::string& what, const ErrorLocation& where,
                             const PluginRegistry& registry) {
  if (!registry.find(s.plugin))
    throw InputError(where, what + ": settings for unknown plugin '" + s.plugin + "'" + plugin_hint(registry, s.plugin));
  PluginSettings settings;
  settings.where = ErrorLocation{where.file, where.line, ""};
  for (const auto& f : s.fields) {
    try {
      settings.set(f.key, setting_value(f.value, s.plugin, f.key));
    } catch (const InputError& e) {
      throw InputError(where, e.bare());
    }
  }
  return settings;
}

WorldDef make_world_def(const RecordedWorld& w, const PluginRegistry& registry) {
  WorldDef def;
  const ErrorLocation& where = w.where;
  auto fail = [&](const std::string& msg) { throw InputError(where, msg); };
  if (w.dt) {
    if (!std::isfinite(*w.dt) || !(*w.dt > 0))
      fail("world: 'dt' must be a positive number of seconds, got " + num(*w.dt));
    def.dt = *w.dt;
  }
  if (!std::isfinite(w.seconds) || w.seconds < 0)
    fail("world: 'seconds' must be a number of seconds >= 0, got " + num(w.seconds));
  for (const auto& p : w.plugins) {
    if (!registry.find(p)) fail("world: unknown plugin '" + p + "'" + plugin_hint(registry, p));
    def.plugins.push_back(p);
  }
  for (const auto& s : w.settings) def.settings[s.plugin] = make_settings(s, "world", where, registry);
  for (const auto& [what, plugin] : w.use) {
    const PluginDef* d = registry.find(plugin);
    if (!d) fail("world: use: unknown plugin '" + plugin + "'" + plugin_hint(registry, plugin));
    if (d->info.provides != what)
      fail("world: use: '" + plugin + "' does not provide '" + what + "'" +
           (d->info.provides.empty() ? std::string() : " (it provides '" + d->info.provides + "')"));
    def.use[what] = plugin;
  }
  for (const RecordedArea& ra : w.areas) {
    AreaDef a;
    a.name = ra.name;
    const std::string what = "world: area '" + ra.name + "'";
    for (const SceneField& f : ra.region) {
      if (f.key == "radius") {
        const double* r = std::get_if<double>(&f.value);
        if (!r || !std::isfinite(*r) || *r <= 0) fail(what + ": 'radius' must be a positive number of metres");
        a.radius = *r;
      } else {
        auto v = vec3_of(f.value);
        if (!v || !is_finite(*v)) fail(what + ": '" + f.key + "' must be a vector {x, y} or {x, y, z}");
        if (f.key == "center") a.center = *v;
        else {
          // A 2D box {hx, hy} reaches through the play area in z.
          if (const auto* n = numbers(f.value); n && n->size() == 2) v->z = 1e9;
          if (v->x <= 0 || v->y <= 0 || v->z <= 0) fail(what + ": 'half_extents' must be positive");
          a.half_extents = *v;
        }
      }
    }
    for (const auto& p : ra.plugins)
      if (!registry.find(p)) fail(what + ": unknown plugin '" + p + "'" + plugin_hint(registry, p));
    a.plugins = ra.plugins;
    for (const auto& s : ra.settings) a.settings[s.plugin] = make_settings(s, what, where, registry);
    def.areas.push_back(std::move(a));
  }
  for (const auto& [plugin, n] : w.every) {
    if (!registry.find(plugin))
      fail("world: 'every' for unknown plugin '" + plugin + "'" + plugin_hint(registry, plugin));
    if (!(n >= 1) || std::floor(n) != n || n > 1e6)
      fail("world: 'every' of '" + plugin + "' must be a whole number of steps >= 1, got " +
           num(n));
    def.every[plugin] = int(n);
  }
  return def;
}

}  // namespace

std::string describe(const SceneValue& v) {
  struct Visitor {
    std::string operator()(double d) const { return "the number " + num(d); }
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(const std::string& s) const { return "the string \"" + s + "\""; }
    std::string operator()(const std::vector<double>& l) const {
      return l.empty() ? "an empty list" : "a list of " + std::to_string(l.size()) + " numbers";
    }
    std::string operator()(const std::vector<std::string>& l) const {
      return "a list of " + std::to_string(l.size()) + " names";
    }
  };
  return std::visit(Visitor{}, v);
}

PropertyValue to_property_value(const SceneValue& value, const PropertyDef& def,
                                const World& world) {
  auto resolve = [&](const std::string& name) {
    const ObjectId id = world.find(name);
    if (id) return id;
    std::vector<std::string> names;
    const PropertyStore& store = world.store();
    for (std::uint32_t s = 0; s < store.slot_count(); ++s)
      if (ObjectId o = store.id_at(s); o) names.push_back(store.describe(o));
    std::string msg = "'" + def.name + "' refers to '" + name + "', but no object has that name";
    if (auto near = closest_name(name, names); !near.empty())
      msg += " (did you mean '" + near + "'?)";
    throw InputError(msg);
  };

  switch (def.kind) {
    case PropertyKind::Number:
      if (const double* d = std::get_if<double>(&value)) return *d;
      wrong_type(def, "a number", value);
    case PropertyKind::Integer:
      if (const double* d = std::get_if<double>(&value);
          d && std::isfinite(*d) && std::floor(*d) == *d)
        return std::int64_t(*d);
      wrong_type(def, "a whole number", value);
    case PropertyKind::Bool:
      if (const bool* b = std::get_if<bool>(&value)) return *b;
      wrong_type(def, "true or false", value);
    case PropertyKind::Vec3:
      if (auto v = vec3_of(value)) return *v;
      wrong_type(def, "a vector {x, y} or {x, y, z}", value);
    case PropertyKind::Quat:
      if (const auto* n = numbers(value); n && n->size() == 4) {
        const Quat q{(*n)[0], (*n)[1], (*n)[2], (*n)[3]};
        const double norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
        // A hand-written quaternion is rarely exactly unit; normalise it here
        // (zero and non-finite ones are refused by the value rules).
        if (norm > 0 && std::isfinite(norm))
          return Quat{q.w / norm, q.x / norm, q.y / norm, q.z / norm};
        return q;
      }
      wrong_type(def, "a quaternion {w, x, y, z}", value);
    case PropertyKind::String:
      if (const std::string* s = std::get_if<std::string>(&value)) return *s;
      wrong_type(def, "a string", value);
    case PropertyKind::Ref:
      if (const std::string* s = std::get_if<std::string>(&value)) return resolve(*s);
      wrong_type(def, "the name of an object", value);
    case PropertyKind::RefList: {
      RefList out;
      if (const auto* names = std::get_if<std::vector<std::string>>(&value)) {
        for (const auto& n : *names) out.push_back(resolve(n));
        return out;
      }
      if (const auto* n = numbers(value); n && n->empty()) return out;
      wrong_type(def, "a list of object names", value);
    }
    case PropertyKind::Enum:
      if (const std::string* s = std::get_if<std::string>(&value)) {
        if (!world.properties().enum_value(world.properties().id(def.name), *s)) {
          std::string allowed;
          for (const auto& v : def.enum_values) allowed += (allowed.empty() ? "" : ", ") + v;
          std::string msg =
              "'" + def.name + "' has no value '" + *s + "' (one of: " + allowed + ")";
          throw InputError(msg);
        }
        return *s;  // the store turns the name into its index
      }
      wrong_type(def, "one of its named values", value);
  }
  wrong_type(def, "a value", value);
}

BuiltScene build_scene(const SceneRecord& record, PluginRegistry& registry) {
  BuiltScene out;
  out.def = make_world_def(record.world, registry);
  try {
    out.world = std::make_unique<World>(registry, out.def);
  } catch (const InputError& e) {
    throw InputError(record.world.where, e.bare());
  }
  World& world = *out.world;

  // Names first, so that every reference can be resolved whatever the order
  // the scene defined its objects in.
  std::vector<ObjectId> ids;
  ids.reserve(record.objects.size());
  for (const RecordedObject& obj : record.objects) {
    if (!obj.name.empty()) {
      if (auto it = out.sources.find(obj.name); it != out.sources.end())
        throw InputError(obj.where, "duplicate name: '" + obj.name +
                                        "' is already the name of the object at " +
                                        it->second.file + ":" + std::to_string(it->second.line));
      out.sources.emplace(obj.name, obj.where);
    }
    ids.push_back(world.create(obj.name));
  }

  const PropertyRegistry& properties = registry.properties();
  for (std::size_t i = 0; i < record.objects.size(); ++i) {
    const RecordedObject& obj = record.objects[i];
    try {
      for (const SceneField& f : obj.fields) {
        const PropertyId pid =
            properties.id(f.key);  // "unknown property 'mas' (did you mean 'mass'?)"
        const PropertyDef& def = properties.def(pid);
        const PropertyValue value = to_property_value(f.value, def, world);
        world.set(ids[i], pid, value);
      }
    } catch (const InputError& e) {
      throw InputError(obj.where, e.bare());
    }
  }
  // Whole-object checks once every object has all its properties (a joint's
  // body may be defined after the joint).
  for (std::size_t i = 0; i < record.objects.size(); ++i) {
    try {
      world.check(ids[i]);
    } catch (const InputError& e) {
      throw InputError(record.objects[i].where, e.bare());
    }
  }
  for (const RecordedSwap& sw : record.swaps) {
    try {
      if (!sw.area.empty() && std::none_of(out.def.areas.begin(), out.def.areas.end(),
                                           [&](const AreaDef& a) { return a.name == sw.area; }))
        throw InputError("swap(): no area is called '" + sw.area + "'");
      for (const std::string* p : {&sw.from, &sw.to})
        if (!registry.find(*p)) throw InputError("swap(): unknown plugin '" + *p + "'" + plugin_hint(registry, *p));
      world.schedule_swap(sw.time, sw.area, sw.from, sw.to);
    } catch (const InputError& e) {
      throw InputError(sw.where, e.bare());
    }
  }
  // The timeline: each input is typed and checked now, applied when its time comes.
  for (const RecordedInput& in : record.inputs) {
    try {
      const ObjectId id = world.find(in.object);
      if (!id) throw InputError("at(): no object is called '" + in.object + "'");
      for (const SceneField& f : in.fields) {
        const PropertyId pid = properties.id(f.key);
        const PropertyDef& def = properties.def(pid);
        if (def.name == "name") throw InputError("at(): an object's name cannot change");
        const PropertyValue value = to_property_value(f.value, def, world);
        world.schedule(in.time, id, pid, value);
      }
    } catch (const InputError& e) {
      throw InputError(in.where, e.bare());
    }
  }
  return out;
}

}  // namespace alloy::lua
