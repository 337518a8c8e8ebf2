#include "lua/scene_bindings.hpp"

#include <algorithm>
#include <cmath>

#include "lua/lua_bridge.hpp"
#include "lua/lua_host.hpp"
#include "lua/lua_values.hpp"
#include "runtime/property_types.hpp"

namespace alloy::lua {

namespace {

const std::vector<std::string> kWorldFields = {"name",    "description", "dt",   "seconds",
                                               "plugins", "settings",    "every"};

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
