#include "lua/mod_loader.hpp"

#include <algorithm>
#include <cctype>

#include "lua/alloy_api.hpp"
#include "lua/lua_bridge.hpp"
#include "lua/lua_host.hpp"
#include "lua/lua_values.hpp"
#include "lua/sandbox.hpp"
#include "runtime/property_types.hpp"

namespace alloy::lua {

namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kManifestFields = {"name",  "version", "description", "depends",
                                                  "scene", "main",    "runtime"};

bool is_identifier(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

/// "kit.parts.bodies" -> {"kit", "parts", "bodies"}; empty if not a module name.
std::vector<std::string> module_segments(const std::string& name) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (;;) {
    const std::size_t dot = name.find('.', start);
    out.push_back(name.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (!is_identifier(out.back())) return {};
    if (dot == std::string::npos) return out;
    start = dot + 1;
  }
}

constexpr HostOptions kManifestLimits{/*memory*/ 4u << 20, /*instructions*/ 10'000'000,
                                      /*seconds*/ 2, /*pattern steps*/ 1'000'000};

std::string folder_name(const fs::path& folder) {
  fs::path p = folder.lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  if (p.filename() == "." || p.filename().empty()) p = fs::absolute(p).lexically_normal();
  return p.filename().string();
}

}  // namespace

std::string display_path(const fs::path& p) {
  std::string s = p.lexically_normal().string();
  return s.empty() ? "." : s;
}

fs::path contained_file(const std::string& mod, const fs::path& folder, const fs::path& file,
                        const ErrorLocation& where) {
  std::error_code ec;
  const fs::path root = fs::canonical(folder, ec);
  if (ec) return file;
  if (!fs::exists(fs::symlink_status(file, ec))) return file;
  // canonical follows every link (a dangling one fails, and is refused too:
  // it may point outside and be created later).
  const fs::path real = fs::canonical(file, ec);
  const fs::path rel = ec ? fs::path("..") : real.lexically_relative(root);
  if (rel.empty() || *rel.begin() == "..")
    throw InputError(where,
                     "mod '" + mod + "': " + display_path(file) +
                         (ec ? std::string(" is a link to nowhere")
                             : " leads outside the mod's folder (to " + real.string() + ")") +
                         "; a mod's files must be inside its folder (no symlink or '..' "
                         "out of it)");
  return real;
}

Manifest read_manifest(LuaHost&, const fs::path& folder) {
  // A manifest is data: it runs in a small host of its own, whatever host
  // asked for it, with tight limits (a loop, a string bomb or a pattern bomb
  // in mod.lua must not hang `alloy run` or a mod runtime).
  LuaHost host(kManifestLimits);
  lua_State* L = host.state();
  const fs::path file = folder / "mod.lua";
  Manifest m;
  m.folder = folder;
  m.file = display_path(file);
  const ErrorLocation where{m.file, 0, ""};
  if (!fs::is_regular_file(file))
    throw InputError(where, "no mod.lua here: a mod folder needs a manifest");

  StackGuard guard(L);
  host.load_file(contained_file(folder_name(folder), folder, file, where), m.file);
  lua_newtable(L);  // a manifest is data: it gets no functions at all
  lua_setfenv(L, -2);
  host.call(0, 1, where);
  if (!lua_istable(L, -1))
    throw InputError(where,
                     "mod.lua must return a table such as { name = \"kit\", version = \"0.1.0\" }");
  const int t = lua_gettop(L);
  std::vector<std::string> keys;
  try {
    keys = sorted_keys(L, t, "manifest fields");
  } catch (const InputError& e) {
    throw InputError(where, e.bare());
  }
  for (const auto& key : keys) {
    if (std::find(kManifestFields.begin(), kManifestFields.end(), key) == kManifestFields.end()) {
      std::string msg = "mod.lua has no field '" + key + "'";
      if (auto near = closest_name(key, kManifestFields); !near.empty())
        msg += " (did you mean '" + near + "'?)";
      throw InputError(where, msg);
    }
    lua_getfield(L, t, key.c_str());
    SceneValue v;
    try {
      v = to_scene_value(L, -1);
    } catch (const InputError& e) {
      throw InputError(where, "mod.lua '" + key + "': " + e.bare());
    }
    lua_pop(L, 1);
    if (key == "depends") {
      if (auto* names = std::get_if<std::vector<std::string>>(&v))
        m.depends = *names;
      else if (!(std::holds_alternative<std::vector<double>>(v) &&
                 std::get<std::vector<double>>(v).empty()))
        throw InputError(where, "mod.lua 'depends' must be a list of mod names, such as {\"kit\"}");
      continue;
    }
    const std::string* s = std::get_if<std::string>(&v);
    if (!s) throw InputError(where, "mod.lua '" + key + "' must be a string");
    if (key == "name")
      m.name = *s;
    else if (key == "version")
      m.version = *s;
    else if (key == "description")
      m.description = *s;
    else if (key == "scene")
      m.scene = *s;
    else if (key == "main")
      m.main = *s;
    else if (key == "runtime")
      m.runtime = *s;
  }
  // Files named by the manifest stay inside the mod's folder.
  for (const auto& [field, value] : {std::pair<const char*, const std::string*>{"main", &m.main},
                                     {"scene", &m.scene},
                                     {"runtime", &m.runtime}}) {
    const fs::path p(*value);
    const bool outside =
        p.is_absolute() ||
        std::any_of(p.begin(), p.end(), [](const fs::path& part) { return part == ".."; });
    if (outside)
      throw InputError(where, std::string("mod.lua '") + field +
                                  "' must name a file inside the mod's folder, not '" + *value +
                                  "'");
  }
  for (const std::string* value : {&m.main, &m.scene, &m.runtime})
    if (!value->empty()) contained_file(folder_name(folder), folder, folder / *value, where);
  if (m.name.empty()) throw InputError(where, "mod.lua must give the mod's name");
  if (!is_identifier(m.name))
    throw InputError(where, "mod name '" + m.name + "' must be letters, digits and _ only");
  if (m.name != folder_name(folder))
    throw InputError(where, "mod.lua names the mod '" + m.name + "' but its folder is '" +
                                folder_name(folder) + "': mods are found by folder name");
  return m;
}

ModLoader::ModLoader(LuaHost& host, std::vector<fs::path> search_path, Decorate decorate)
    : host_(host), search_path_(std::move(search_path)), decorate_(std::move(decorate)) {
  // Caches of this loader alone: a second loader in the same state (a mod
  // reloaded) starts from nothing and runs every file again.
  lua_State* L = host_.state();
  box_ = static_cast<ModLoader**>(lua_newuserdata(L, sizeof(ModLoader*)));
  *box_ = this;
  box_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
  lua_newtable(L);
  envs_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
  lua_newtable(L);
  loaded_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
  lua_newtable(L);
  views_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
}

ModLoader::~ModLoader() {
  lua_State* L = host_.state();
  *box_ = nullptr;
  luaL_unref(L, LUA_REGISTRYINDEX, box_ref_);
  luaL_unref(L, LUA_REGISTRYINDEX, envs_ref_);
  luaL_unref(L, LUA_REGISTRYINDEX, loaded_ref_);
  luaL_unref(L, LUA_REGISTRYINDEX, views_ref_);
}

void ModLoader::set_scene_mod(std::optional<Manifest> manifest) {
  scene_mod_ = std::move(manifest);
}

void ModLoader::add_scene_file(const std::string& display) {
  file_mod_[display] = "";
}

void ModLoader::push_environment(const std::string& mod) {
  lua_State* L = host_.state();
  const std::string key = (mod == scene_mod_name()) ? "" : mod;
  lua_rawgeti(L, LUA_REGISTRYINDEX, envs_ref_);
  lua_getfield(L, -1, key.c_str());
  if (lua_istable(L, -1)) {
    lua_remove(L, -2);
    return;
  }
  lua_pop(L, 1);
  lua::push_environment(L);
  const int env = lua_gettop(L);
  decorate_(L, env, key);
  lua_rawgeti(L, LUA_REGISTRYINDEX, box_ref_);
  lua_pushstring(L, key.c_str());  // who requires: this environment's mod ("" = the scene's)
  lua_pushcclosure(L, &ModLoader::require_fn, 2);
  lua_setfield(L, env, "require");
  lua_pushvalue(L, env);
  lua_setfield(L, -3, key.c_str());
  lua_remove(L, -2);
}

const Manifest* ModLoader::find(const std::string& name) {
  if (scene_mod_ && scene_mod_->name == name) return &*scene_mod_;
  auto it = manifests_.find(name);
  if (it == manifests_.end()) {
    std::optional<Manifest> found;
    for (const auto& dir : search_path_)
      if (fs::is_regular_file(dir / name / "mod.lua")) {
        found = read_manifest(host_, dir / name);
        break;
      }
    it = manifests_.emplace(name, std::move(found)).first;
  }
  return it->second ? &*it->second : nullptr;
}

std::vector<std::string> ModLoader::available() const {
  std::vector<std::string> out;
  for (const auto& dir : search_path_) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir, ec))
      if (entry.is_directory() && fs::is_regular_file(entry.path() / "mod.lua"))
        out.push_back(entry.path().filename().string());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void ModLoader::check_depends(const Manifest& m) {
  if (std::find(checked_.begin(), checked_.end(), m.name) != checked_.end()) return;
  for (const auto& dep : m.depends)
    if (!find(dep))
      throw InputError(ErrorLocation{m.file, 0, ""}, "mod '" + m.name + "' depends on '" + dep +
                                                         "', which is not on the mod path");
  checked_.push_back(m.name);
}

int ModLoader::require_fn(lua_State* L) {
  auto** box = static_cast<ModLoader**>(lua_touserdata(L, lua_upvalueindex(1)));
  ModLoader* self = box ? *box : nullptr;
  if (!self) return luaL_error(L, "require: the files this function came from were unloaded");
  return catch_exceptions(L, [&] { return self->require(L); });
}

int ModLoader::require(lua_State* L) {
  const std::string name = luaL_checkstring(L, 1);
  const char* env_mod = lua_tostring(L, lua_upvalueindex(2));
  const std::string requirer = env_mod && *env_mod ? env_mod : scene_mod_name();
  lua_settop(L, 1);

  const std::vector<std::string> segments = module_segments(name);
  if (segments.empty())
    throw InputError(
        "require \"" + name +
        "\": a module name is a mod name, optionally followed by "
        "dot-separated file names (\"kit\", \"kit.materials\"); paths are not allowed");
  const std::string& mod = segments[0];

  if (!requirer.empty() && requirer != mod) {
    const Manifest* cm = find(requirer);
    if (cm && std::find(cm->depends.begin(), cm->depends.end(), mod) == cm->depends.end())
      throw InputError("mod '" + requirer + "' requires '" + mod +
                       "' but its mod.lua does not list it in depends");
  }

  lua_rawgeti(L, LUA_REGISTRYINDEX, loaded_ref_);  // 2
  lua_getfield(L, 2, name.c_str());
  if (!lua_isnil(L, -1)) return deliver(L, name, mod, requirer);
  lua_pop(L, 1);

  const Manifest* m = find(mod);
  if (!m) {
    std::string msg = "no mod named '" + mod + "' on the mod path (";
    for (std::size_t i = 0; i < search_path_.size(); ++i)
      msg += (i ? ", " : "") + display_path(search_path_[i]);
    msg += ")";
    if (auto near = closest_name(mod, available()); !near.empty())
      msg += "; did you mean '" + near + "'?";
    throw InputError(msg);
  }
  check_depends(*m);

  fs::path file = m->folder;
  if (segments.size() == 1) {
    file /= m->main;
  } else {
    for (std::size_t i = 1; i < segments.size(); ++i) file /= segments[i];
    file += ".lua";
  }
  const std::string display = display_path(file);
  fs::path real;
  try {
    real = contained_file(mod, m->folder, file);
  } catch (const InputError& e) {
    throw InputError(library_caller(L) + e.bare());
  }
  if (!fs::is_regular_file(real))
    throw InputError("require \"" + name + "\": mod '" + mod + "' has no file " + display);

  if (std::find(loading_.begin(), loading_.end(), name) != loading_.end()) {
    std::string chain;
    for (const auto& n : loading_) chain += n + " -> ";
    throw InputError("require cycle: " + chain + name);
  }
  loading_.push_back(name);
  struct PopOnExit {  // also when the module fails and Lua unwinds through here
    std::vector<std::string>& v;
    ~PopOnExit() { v.pop_back(); }
  } pop{loading_};

  const bool user_code = m->name == scene_mod_name();
  file_mod_[display] = user_code ? "" : m->name;
  if (!user_code && std::find(required_.begin(), required_.end(), m->name) == required_.end())
    required_.push_back(m->name);
  if (!user_code) host_.mark_library(display);
  host_.load_file(real, display);  // 3: the chunk
  push_environment(m->name);
  lua_setfenv(L, 3);
  lua_pushvalue(L, 1);
  lua_call(L, 1, 1);  // unprotected on purpose: an error reaches the scene's protected call
  if (lua_isnil(L, -1)) {
    lua_pop(L, 1);
    lua_pushboolean(L, 1);
  }
  lua_pushvalue(L, -1);
  lua_setfield(L, 2, name.c_str());
  return deliver(L, name, m->name, requirer);
}

std::string ModLoader::library_caller(lua_State* L) const {
  lua_Debug ar;
  if (lua_getstack(L, 1, &ar) && lua_getinfo(L, "Sl", &ar) && ar.source && ar.source[0] == '@' &&
      ar.currentline > 0 && host_.is_library(ar.source + 1))
    return std::string(ar.source + 1) + ":" + std::to_string(ar.currentline) + ": ";
  return "";
}

int ModLoader::deliver(lua_State* L, const std::string& name, const std::string& mod,
                       const std::string& requirer) {
  const int value = lua_gettop(L);
  const bool per_mod = push_per_mod_function(L, value);  // pushes f
  const bool foreign = requirer != mod;
  if (!per_mod && !(foreign && lua_istable(L, value) && !is_frozen(L, value))) return 1;
  const std::string key = name + "|" + requirer;
  lua_rawgeti(L, LUA_REGISTRYINDEX, views_ref_);
  const int views = lua_gettop(L);
  lua_getfield(L, views, key.c_str());
  if (!lua_isnil(L, -1)) return 1;
  lua_pop(L, 1);
  if (per_mod) {
    lua_pushvalue(L, value + 1);
    lua_pushstring(L, requirer.c_str());
    lua_call(L, 1, 1);  // unprotected, as the module's own chunk
    if (lua_isnil(L, -1))
      throw InputError(library_caller(L) + "require \"" + name + "\": mod '" + mod +
                       "' keeps this module to itself; " +
                       (requirer.empty() ? std::string("the scene") : "mod '" + requirer + "'") +
                       " cannot use it (require \"" + mod + "\")");
  } else {
    lua_pushvalue(L, value);
  }
  // Another mod's table is theirs: read it, call it, never change it.
  if (foreign && lua_istable(L, -1) && !is_frozen(L, -1)) {
    push_frozen(L, -1);
    lua_remove(L, -2);
  }
  lua_pushvalue(L, -1);
  lua_setfield(L, views, key.c_str());
  return 1;
}

}  // namespace alloy::lua
