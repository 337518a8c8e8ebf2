#include "lua/scene_bindings.hpp"

#include <algorithm>
#include <cmath>

#include "lua/lua_bridge.hpp"
#include "lua/lua_host.hpp"
#include "lua/lua_values.hpp"
#include "runtime/property_types.hpp"

namespace alloy::lua {

namespace {

const std::vector<std::string> kWorldFields = {"name",    "description", "dt",    "seconds",
                                               "plugins", "settings",    "every", "use",
                                               "areas",   "report",      "grants"};
const std::vector<std::string> kAreaFields = {"name", "center", "half_extents", "radius", "plugins",
                                              "settings"};

SceneRecorder* self(lua_State* L) {
  return static_cast<SceneRecorder*>(lua_touserdata(L, lua_upvalueindex(1)));
}

// The value of field `key` of the table at `t` (raw: no script metamethod runs).
void raw_field(lua_State* L, int t, const std::string& key) {
  lua_pushlstring(L, key.data(), key.size());
  lua_rawget(L, t);
}

double number_field(lua_State* L, int t, const std::string& key, const ErrorLocation& where) {
  raw_field(L, t, key);
  if (lua_type(L, -1) != LUA_TNUMBER)
    throw InputError(where, "world: '" + key + "' must be a number");
  const double v = lua_tonumber(L, -1);
  lua_pop(L, 1);
  return v;
}

std::string string_field(lua_State* L, int t, const std::string& key, const ErrorLocation& where) {
  raw_field(L, t, key);
  if (lua_type(L, -1) != LUA_TSTRING)
    throw InputError(where, "world: '" + key + "' must be a string");
  std::string v = lua_tostring(L, -1);
  lua_pop(L, 1);
  return v;
}

std::vector<SceneField> fields_of(lua_State* L, int t, const std::string& what,
                                  const ErrorLocation& where) {
  std::vector<SceneField> out;
  std::vector<std::string> keys;
  try {
    keys = sorted_keys(L, t, what);
  } catch (const InputError& e) {
    throw InputError(where, e.bare());
  }
  for (const auto& key : keys) {
    raw_field(L, t, key);
    try {
      out.push_back({key, to_scene_value(L, -1)});
    } catch (const InputError& e) {
      throw InputError(where, what + " '" + key + "': " + e.bare());
    }
    lua_pop(L, 1);
  }
  return out;
}

}  // namespace

void SceneRecorder::install(lua_State* L, int env) {
  env = abs_index(L, env);
  lua_pushlightuserdata(L, this);
  lua_pushcclosure(L, &SceneRecorder::world_fn, 1);
  lua_setfield(L, env, "world");
  lua_pushlightuserdata(L, this);
  lua_pushcclosure(L, &SceneRecorder::object_fn, 1);
  lua_setfield(L, env, "object");
  lua_pushlightuserdata(L, this);
  lua_pushcclosure(L, &SceneRecorder::at_fn, 1);
  lua_setfield(L, env, "at");
  lua_pushlightuserdata(L, this);
  lua_pushcclosure(L, &SceneRecorder::swap_fn, 1);
  lua_setfield(L, env, "swap");
}

int SceneRecorder::swap_fn(lua_State* L) {
  return catch_exceptions(L, [&] { return self(L)->record_swap(L); });
}

int SceneRecorder::record_swap(lua_State* L) {
  RecordedSwap sw;
  sw.where = host_.user_location(L);
  if (lua_type(L, 1) != LUA_TNUMBER || lua_type(L, 2) != LUA_TSTRING || lua_type(L, 3) != LUA_TSTRING ||
      lua_type(L, 4) != LUA_TSTRING)
    throw InputError(sw.where, "swap(time, \"area\" or \"\", \"from\", \"to\") expects a time in seconds, "
                               "an area's name (\"\" for everywhere) and two plugin names");
  sw.time = lua_tonumber(L, 1);
  if (!std::isfinite(sw.time) || sw.time < 0)
    throw InputError(sw.where, "swap(): the time must be a number of seconds >= 0");
  sw.area = lua_tostring(L, 2);
  sw.from = lua_tostring(L, 3);
  sw.to = lua_tostring(L, 4);
  record_.swaps.push_back(std::move(sw));
  return 0;
}

int SceneRecorder::at_fn(lua_State* L) {
  return catch_exceptions(L, [&] { return self(L)->record_input(L); });
}

int SceneRecorder::record_input(lua_State* L) {
  RecordedInput in;
  in.where = host_.user_location(L);
  const char* usage = "at(time, \"object\", { property = value, ... }) expects a time in seconds, "
                      "an object's name and a table of properties";
  if (lua_type(L, 1) != LUA_TNUMBER || lua_type(L, 2) != LUA_TSTRING || lua_type(L, 3) != LUA_TTABLE)
    throw InputError(in.where, usage);
  lua_settop(L, 3);
  in.time = lua_tonumber(L, 1);
  in.object = lua_tostring(L, 2);
  in.where.object = in.object;
  if (!std::isfinite(in.time) || in.time < 0)
    throw InputError(in.where, "at(): the time must be a number of seconds >= 0");
  in.fields = fields_of(L, 3, "property", in.where);
  if (in.fields.empty()) throw InputError(in.where, "at(): nothing to set");
  record_.inputs.push_back(std::move(in));
  return 0;
}

int SceneRecorder::world_fn(lua_State* L) {
  return catch_exceptions(L, [&] { return self(L)->record_world(L); });
}

int SceneRecorder::object_fn(lua_State* L) {
  return catch_exceptions(L, [&] { return self(L)->record_object(L); });
}

int SceneRecorder::record_object(lua_State* L) {
  RecordedObject obj;
  obj.where = host_.user_location(L);
  obj.where.object = "#" + std::to_string(record_.objects.size() + 1);
  if (lua_type(L, 1) != LUA_TTABLE)
    throw InputError(
        obj.where,
        "object{} expects a table of properties, e.g. object { name = \"ball\", mass = 1 }");
  lua_settop(L, 1);

  raw_field(L, 1, "name");
  if (lua_type(L, -1) == LUA_TSTRING) {
    obj.name = lua_tostring(L, -1);
    if (obj.name.empty()) throw InputError(obj.where, "'name' must not be empty");
    obj.where.object = obj.name;
  } else if (!lua_isnil(L, -1)) {
    throw InputError(obj.where,
                     std::string("'name' must be a string, not a ") + luaL_typename(L, -1));
  }
  lua_pop(L, 1);

  obj.fields = fields_of(L, 1, "property", obj.where);
  std::erase_if(obj.fields, [](const SceneField& f) { return f.key == "name"; });
  record_.objects.push_back(std::move(obj));
  // The name back, so that a script can write  local arm = object { name = "arm", ... }
  if (record_.objects.back().name.empty()) return 0;
  lua_pushstring(L, record_.objects.back().name.c_str());
  return 1;
}

int SceneRecorder::record_world(lua_State* L) {
  RecordedWorld& w = record_.world;
  const ErrorLocation where = host_.user_location(L);
  if (w.given)
    throw InputError(where, "world{} is given twice (first at " + w.where.file + ":" +
                                std::to_string(w.where.line) + ")");
  if (lua_type(L, 1) != LUA_TTABLE)
    throw InputError(where, "world{} expects a table, e.g. world { dt = 1/240, seconds = 5 }");
  lua_settop(L, 1);
  w.given = true;
  w.where = where;

  std::vector<std::string> keys;
  try {
    keys = sorted_keys(L, 1, "world fields");
  } catch (const InputError& e) {
    throw InputError(where, e.bare());
  }
  for (const auto& key : keys) {
    if (std::find(kWorldFields.begin(), kWorldFields.end(), key) == kWorldFields.end()) {
      std::string msg = "world has no field '" + key + "'";
      if (auto near = closest_name(key, kWorldFields); !near.empty())
        msg += " (did you mean '" + near + "'?)";
      throw InputError(where, msg);
    }
    if (key == "name")
      w.name = string_field(L, 1, key, where);
    else if (key == "description")
      w.description = string_field(L, 1, key, where);
    else if (key == "dt")
      w.dt = number_field(L, 1, key, where);
    else if (key == "seconds")
      w.seconds = number_field(L, 1, key, where);
    else if (key == "plugins") {
      raw_field(L, 1, key);
      SceneValue v;
      try {
        v = to_scene_value(L, -1);
      } catch (const InputError& e) {
        throw InputError(where, "world: 'plugins' " + e.bare());
      }
      lua_pop(L, 1);
      if (auto* names = std::get_if<std::vector<std::string>>(&v))
        w.plugins = *names;
      else if (!std::holds_alternative<std::vector<double>>(v) ||
               !std::get<std::vector<double>>(v).empty())
        throw InputError(where, "world: 'plugins' must be a list of plugin names");
    } else if (key == "report") {
      raw_field(L, 1, key);
      SceneValue v = to_scene_value(L, -1);
      lua_pop(L, 1);
      if (auto* specs = std::get_if<std::vector<std::string>>(&v)) w.report = *specs;
      else if (auto* one = std::get_if<std::string>(&v)) w.report = {*one};
      else throw InputError(where, "world: 'report' must be a list such as { \"axle.angular_velocity.z@1\" }");
    } else if (key == "use") {
      raw_field(L, 1, key);
      const int t = lua_gettop(L);
      if (lua_type(L, t) != LUA_TTABLE)
        throw InputError(where, "world: 'use' must be a table such as { gravity = \"gravity.nbody\" }");
      for (const SceneField& f : fields_of(L, t, "use", where)) {
        const std::string* plugin = std::get_if<std::string>(&f.value);
        if (!plugin) throw InputError(where, "world: 'use' of '" + f.key + "' must be a plugin name");
        w.use.emplace_back(f.key, *plugin);
      }
      lua_pop(L, 1);
    } else if (key == "areas") {
      raw_field(L, 1, key);
      const int t = lua_gettop(L);
      if (lua_type(L, t) != LUA_TTABLE)
        throw InputError(where, "world: 'areas' must be a list of areas such as "
                                "{ name = \"orbit\", plugins = {\"gravity.nbody\"} }");
      const int n = int(lua_objlen(L, t));
      for (int i = 1; i <= n; ++i) {
        lua_rawgeti(L, t, i);
        const int a = lua_gettop(L);
        const std::string what = "world: area " + std::to_string(i);
        if (lua_type(L, a) != LUA_TTABLE) throw InputError(where, what + " must be a table");
        RecordedArea area;
        for (const std::string& k : sorted_keys(L, a, what)) {
          if (std::find(kAreaFields.begin(), kAreaFields.end(), k) == kAreaFields.end()) {
            std::string msg = what + " has no field '" + k + "'";
            if (auto near = closest_name(k, kAreaFields); !near.empty()) msg += " (did you mean '" + near + "'?)";
            throw InputError(where, msg);
          }
          raw_field(L, a, k);
          const int v = lua_gettop(L);
          if (k == "name") {
            if (lua_type(L, v) != LUA_TSTRING) throw InputError(where, what + ": 'name' must be a string");
            area.name = lua_tostring(L, v);
          } else if (k == "settings") {
            if (lua_type(L, v) != LUA_TTABLE) throw InputError(where, what + ": 'settings' must be a table keyed by plugin name");
            for (const std::string& plugin : sorted_keys(L, v, what + " settings")) {
              raw_field(L, v, plugin);
              if (lua_type(L, -1) != LUA_TTABLE)
                throw InputError(where, what + ": the settings of '" + plugin + "' must be a table");
              area.settings.push_back({plugin, fields_of(L, lua_gettop(L), "setting", where)});
              lua_pop(L, 1);
            }
          } else if (k == "plugins") {
            SceneValue pv = to_scene_value(L, v);
            if (auto* names = std::get_if<std::vector<std::string>>(&pv)) area.plugins = *names;
            else throw InputError(where, what + ": 'plugins' must be a list of plugin names");
          } else {
            area.region.push_back({k, to_scene_value(L, v)});
          }
          lua_pop(L, 1);
        }
        if (area.name.empty()) throw InputError(where, what + " needs a name");
        w.areas.push_back(std::move(area));
        lua_pop(L, 1);
      }
      lua_pop(L, 1);
    } else if (key == "grants") {
      raw_field(L, 1, key);
      const int t = lua_gettop(L);
      const char* example = "world: 'grants' must be a table such as { magic = { \"velocity\" } }";
      if (lua_type(L, t) != LUA_TTABLE) throw InputError(where, example);
      std::vector<std::string> mods;
      try {
        mods = sorted_keys(L, t, "world: 'grants'");
      } catch (const InputError& e) {
        throw InputError(where, e.bare());
      }
      for (const auto& mod : mods) {
        raw_field(L, t, mod);
        SceneValue v;
        try {
          v = to_scene_value(L, -1);
        } catch (const InputError& e) {
          throw InputError(where, "world: 'grants' of '" + mod + "' " + e.bare());
        }
        lua_pop(L, 1);
        if (auto* names = std::get_if<std::vector<std::string>>(&v))
          w.grants.emplace_back(mod, *names);
        else if (auto* one = std::get_if<std::string>(&v))
          w.grants.emplace_back(mod, std::vector<std::string>{*one});
        else
          throw InputError(where,
                           "world: 'grants' of '" + mod +
                               "' must be a list of property names, such as { \"velocity\" }");
      }
      lua_pop(L, 1);
    } else if (key == "settings" || key == "every") {
      raw_field(L, 1, key);
      const int t = lua_gettop(L);
      if (lua_type(L, t) != LUA_TTABLE)
        throw InputError(where, "world: '" + key + "' must be a table keyed by plugin name");
      std::vector<std::string> plugins;
      try {
        plugins = sorted_keys(L, t, "world: '" + key + "'");
      } catch (const InputError& e) {
        throw InputError(where, e.bare());
      }
      for (const auto& plugin : plugins) {
        raw_field(L, t, plugin);
        if (key == "settings") {
          if (lua_type(L, -1) != LUA_TTABLE)
            throw InputError(where, "world: the settings of '" + plugin +
                                        "' must be a table such as { g = {0, -9.81, 0} }");
          w.settings.push_back({plugin, fields_of(L, lua_gettop(L), "setting", where)});
        } else {
          if (lua_type(L, -1) != LUA_TNUMBER)
            throw InputError(where,
                             "world: 'every' of '" + plugin + "' must be a whole number of steps");
          w.every.emplace_back(plugin, lua_tonumber(L, -1));
        }
        lua_pop(L, 1);
      }
      lua_pop(L, 1);
    }
  }
  return 0;
}

}  // namespace alloy::lua
