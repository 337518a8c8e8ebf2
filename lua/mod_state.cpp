#include "lua/mod_state.hpp"

#include <algorithm>
#include <cmath>
#include <lua.hpp>

#include "lua/alloy_api.hpp"
#include "lua/lua_bridge.hpp"
#include "lua/lua_stages.hpp"
#include "lua/sandbox.hpp"
#include "runtime/property_types.hpp"

namespace alloy::lua {

extern const char* const kStagePreludeSource;  // stage_prelude.lua, embedded by CMake

namespace fs = std::filesystem;

namespace {

constexpr std::int32_t kQuantum = 1000;  // ticks between two checks of the budgets
static_assert(kQuantum <= INT16_MAX);    // abi::Budget::ticks
// Steps of pattern matching (lua_patterns.hpp) that cost one tick. A step
// takes 5-10 ns, about what the tick budget allows a tick (20 million ticks
// and 0.25 s per step).
constexpr std::uint64_t kPatternStepsPerTick = 1;

std::string millions(std::uint64_t n) {
  if (n % 1000000 == 0) return std::to_string(n / 1000000) + " million";
  return std::to_string(n);
}

/// The innermost frame of a file (not the prelude, not C): where the mod was.
ErrorLocation mod_location(lua_State* L) {
  lua_Debug ar;
  for (int level = 0; lua_getstack(L, level, &ar); ++level) {
    if (!lua_getinfo(L, "Sl", &ar)) continue;
    if (ar.source && ar.source[0] == '@' && ar.currentline > 0)
      return {ar.source + 1, ar.currentline, ""};
  }
  return {};
}

/// "64 KiB", "16 MiB", "100 bytes": a budget as its author wrote it.
std::string bytes_text(std::uint64_t n) {
  if (n >= (1u << 20) && n % (1u << 20) == 0) return std::to_string(n >> 20) + " MiB";
  if (n >= (1u << 10) && n % (1u << 10) == 0) return std::to_string(n >> 10) + " KiB";
  return std::to_string(n) + " bytes";
}

/// `s` cut to `limit` bytes, with a note of how much was cut.
std::string cut(const std::string& s, std::size_t limit) {
  if (s.size() <= limit) return s;
  return s.substr(0, limit) + "... (" + std::to_string(s.size() - limit) + " more bytes dropped)";
}

/// The line print(...) writes: its arguments through tostring, tab-separated.
/// Only the first `room` bytes are copied into `line`; returns the length of
/// the whole line with its newline.
std::uint64_t print_line(lua_State* L, std::uint64_t room, std::string& line) {
  std::uint64_t total = 1;  // the newline
  const int n = lua_gettop(L);
  for (int i = 1; i <= n; ++i) {
    lua_getglobal(L, "tostring");
    lua_pushvalue(L, i);
    lua_call(L, 1, 1);
    std::size_t len = 0;
    const char* s = lua_tolstring(L, -1, &len);
    if (!s) s = "?", len = 1;
    if (i > 1) {
      ++total;
      if (line.size() < room) line += '\t';
    }
    total += len;
    if (line.size() < room) line.append(s, std::min<std::size_t>(len, room - line.size()));
    lua_pop(L, 1);
  }
  return total;
}

int sink_print(lua_State* L) {
  auto* sink = static_cast<PrintSink*>(lua_touserdata(L, lua_upvalueindex(1)));
  const std::uint64_t room = sink->used >= sink->limit ? 0 : sink->limit - sink->used;
  std::string line;
  const std::uint64_t total = print_line(L, room, line);
  if (total <= room) {
    sink->used += total;
    sink->write(line);
    return 0;
  }
  sink->used = sink->limit;
  if (!line.empty()) sink->write(line);
  sink->write("... (" + std::to_string(total - line.size()) + " more bytes dropped)");
  std::string().swap(line);
  return luaL_error(L, "%s printed more than %s (a print in a loop?)", sink->who.c_str(),
                    bytes_text(sink->limit).c_str());
}

/// The longest name a mod may give a plugin, a property, an interaction
/// function or a setting, and the most interaction functions one resolver
/// may declare: a listing (`alloy plugins`), an error message or a save
/// stays readable, and a mod cannot make the host hold 100,000-character
/// names or thousands of bindings (docs/security.md).
constexpr std::size_t kMaxNameLength = 64;
constexpr std::size_t kMaxFunctions = 64;

bool valid_name(const std::string& s, bool dots) {
  if (s.empty() || s.size() > kMaxNameLength || std::isdigit(static_cast<unsigned char>(s[0])))
    return false;
  return std::all_of(s.begin(), s.end(), [&](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || (dots && c == '.');
  });
}

}  // namespace

void install_print(lua_State* L, int env, PrintSink* sink) {
  env = abs_index(L, env);
  lua_pushlightuserdata(L, sink);
  lua_pushcclosure(L, sink_print, 1);
  lua_setfield(L, env, "print");
}

bool StageDecl::same_shape(const StageDecl& o) const {
  const StageInfo& a = info;
  const StageInfo& b = o.info;
  return a.name == b.name && a.kind == b.kind && a.reads == b.reads && a.writes == b.writes &&
         a.needs == b.needs && a.derived == b.derived && a.resolvers == b.resolvers &&
         a.target == b.target && a.provides == b.provides && functions == o.functions &&
         provides == o.provides && settings == o.settings;
}

const StageDecl* Program::stage(std::string_view name) const {
  for (const auto& s : stages)
    if (s.info.name == name) return &s;
  return nullptr;
}

// --- the `mod` table: what a runtime file defines -----------------------------------

struct Collector {
  ModState& mod;
  Program& program;
  int mod_ref = -2;  // the `mod` table of this load

  static Collector* from(lua_State* L) {
    auto* box = static_cast<Collector**>(lua_touserdata(L, lua_upvalueindex(1)));
    if (!box || !*box)
      throw InputError(
          "mod.property, mod.resolver, mod.derived, mod.interaction and mod.on "
          "can only be called while the mod's files load");
    return *box;
  }

  ErrorLocation here(lua_State* L) const { return mod.host().user_location(L); }

  void check_fields(lua_State* L, int t, const std::vector<std::string>& allowed,
                    const std::string& what) {
    for (lua_pushnil(L); lua_next(L, t); lua_pop(L, 1)) {
      if (lua_type(L, -2) != LUA_TSTRING)
        throw InputError(here(L), what + " takes named fields only");
      const std::string key = lua_tostring(L, -2);
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        std::string msg = what + " has no field '" + key + "'";
        if (auto near = closest_name(key, allowed); !near.empty())
          msg += " (did you mean '" + near + "'?)";
        throw InputError(here(L), msg);
      }
    }
  }

  std::optional<std::string> string_field(lua_State* L, int t, const char* key,
                                          const std::string& what) {
    lua_getfield(L, t, key);
    std::optional<std::string> out;
    if (lua_type(L, -1) == LUA_TSTRING)
      out = lua_tostring(L, -1);
    else if (!lua_isnil(L, -1))
      throw InputError(here(L),
                       what + ": '" + key + "' must be a string, not a " + luaL_typename(L, -1));
    lua_pop(L, 1);
    return out;
  }

  std::optional<double> number_field(lua_State* L, int t, const char* key,
                                     const std::string& what) {
    lua_getfield(L, t, key);
    std::optional<double> out;
    if (lua_type(L, -1) == LUA_TNUMBER)
      out = lua_tonumber(L, -1);
    else if (!lua_isnil(L, -1))
      throw InputError(here(L), what + ": '" + key + "' must be a number");
    lua_pop(L, 1);
    return out;
  }

  std::vector<std::string> list_field(lua_State* L, int t, const char* key,
                                      const std::string& what) {
    lua_getfield(L, t, key);
    std::vector<std::string> out;
    if (lua_istable(L, -1)) {
      const int n = int(lua_objlen(L, -1));
      for (int i = 1; i <= n; ++i) {
        lua_rawgeti(L, -1, i);
        if (lua_type(L, -1) != LUA_TSTRING)
          throw InputError(here(L), what + ": '" + key + "' must be a list of names");
        out.emplace_back(lua_tostring(L, -1));
        lua_pop(L, 1);
      }
      // A table with named fields where a list is expected is a mistake.
      lua_pushnil(L);
      while (lua_next(L, -2)) {
        lua_pop(L, 1);
        if (lua_type(L, -1) != LUA_TNUMBER)
          throw InputError(here(L),
                           what + ": '" + key + "' must be a list of names, such as {\"mass\"}");
      }
    } else if (!lua_isnil(L, -1)) {
      throw InputError(here(L),
                       what + ": '" + key + "' must be a list of names, such as {\"mass\"}");
    }
    lua_pop(L, 1);
    return out;
  }

  /// A name longer than kMaxNameLength is refused by its length (and
  /// shown cut short: the name itself may be 100,000 characters).
  void check_length(lua_State* L, const std::string& what, const std::string& name) {
    if (name.size() <= kMaxNameLength) return;
    std::string shown = name.substr(0, 24);
    for (char& c : shown)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '.') c = '?';
    throw InputError(here(L),
                     what + ": the name '" + shown + "...' is " + std::to_string(name.size()) +
                         " characters long; names are at most " + std::to_string(kMaxNameLength));
  }

  /// The string keys of the table in field `key`, sorted; the values stay on the Lua side.
  std::vector<std::string> keys_of(lua_State* L, int t, const char* key, const std::string& what) {
    lua_getfield(L, t, key);
    std::vector<std::string> out;
    if (lua_istable(L, -1)) {
      for (lua_pushnil(L); lua_next(L, -2); lua_pop(L, 1)) {
        if (lua_type(L, -2) == LUA_TSTRING) check_length(L, what, lua_tostring(L, -2));
        if (lua_type(L, -2) != LUA_TSTRING || !valid_name(lua_tostring(L, -2), false))
          throw InputError(here(L), what + ": the keys of '" + key + "' must be names");
        out.emplace_back(lua_tostring(L, -2));
      }
    } else if (!lua_isnil(L, -1)) {
      throw InputError(here(L), what + ": '" + key + "' must be a table");
    }
    lua_pop(L, 1);
    std::sort(out.begin(), out.end());
    return out;
  }

  void property(lua_State* L) {
    luaL_checktype(L, 1, LUA_TTABLE);
    const std::string what = "mod.property";
    check_fields(L, 1, {"name", "kind", "unit", "doc", "min", "max", "min_exclusive", "values"},
                 what);
    PropertyDef def;
    def.name = string_field(L, 1, "name", what).value_or("");
    check_length(L, what, def.name);
    if (!valid_name(def.name, false))
      throw InputError(here(L),
                       what + " needs a name made of letters, digits and _ (name = \"mana\")");
    const std::string kind = string_field(L, 1, "kind", what).value_or("number");
    auto k = kind_from_string(kind);
    if (!k)
      throw InputError(here(L),
                       what + " '" + def.name + "': unknown kind '" + kind +
                           "' (number, integer, bool, vec3, quat, string, ref, reflist, enum)");
    def.kind = *k;
    def.unit = string_field(L, 1, "unit", what).value_or("");
    def.doc = string_field(L, 1, "doc", what).value_or("");
    def.min = number_field(L, 1, "min", what);
    def.max = number_field(L, 1, "max", what);
    lua_getfield(L, 1, "min_exclusive");
    def.min_exclusive = lua_toboolean(L, -1);
    lua_pop(L, 1);
    def.enum_values = list_field(L, 1, "values", what);
    if (def.kind == PropertyKind::Enum && def.enum_values.empty())
      throw InputError(here(L), what + " '" + def.name +
                                    "': an enum needs its values, e.g. values = {\"a\", \"b\"}");
    def.owner = mod.name();
    def.owner_is_mod = true;
    for (const auto& p : program.properties)
      if (p.name == def.name)
        throw InputError(here(L), what + " '" + def.name + "' is defined twice");
    program.properties.push_back(std::move(def));
    program.property_where.push_back(here(L));
  }

  void stage(lua_State* L, StageKind kind) {
    luaL_checktype(L, 1, LUA_TTABLE);
    const char* fn_name = kind == StageKind::Resolver  ? "resolver"
                          : kind == StageKind::Derived ? "derived"
                                                       : "interaction";
    std::string what = std::string("mod.") + fn_name;
    std::vector<std::string> allowed = {"name", "doc", "reads", "needs", "settings"};
    switch (kind) {
      case StageKind::Resolver:
        allowed.insert(allowed.end(), {"writes", "functions", "build", "advance"});
        break;
      case StageKind::Derived:
        allowed.insert(allowed.end(), {"derived", "resolvers", "provides", "update"});
        break;
      case StageKind::Interaction:
        allowed.insert(allowed.end(), {"derived", "target", "apply"});
        break;
    }
    check_fields(L, 1, allowed, what);
    StageDecl d;
    d.where = here(L);
    d.info.kind = kind;
    d.info.name = string_field(L, 1, "name", what).value_or("");
    check_length(L, what, d.info.name);
    if (!valid_name(d.info.name, true))
      throw InputError(d.where, what + " needs a name made of letters, digits, _ and . (name = \"" +
                                    mod.name() + ".thing\")");
    what += " '" + d.info.name + "'";
    d.info.owner = mod.name();
    d.info.doc = string_field(L, 1, "doc", what).value_or("");
    d.info.reads = list_field(L, 1, "reads", what);
    d.info.needs = list_field(L, 1, "needs", what);
    d.info.writes = list_field(L, 1, "writes", what);
    d.info.derived = list_field(L, 1, "derived", what);
    d.info.resolvers = list_field(L, 1, "resolvers", what);
    d.info.target = string_field(L, 1, "target", what).value_or("");
    if (kind == StageKind::Interaction && d.info.target.empty())
      throw InputError(d.where,
                       what + " needs the one resolver it queues on (target = \"<resolver>\")");
    d.settings = keys_of(L, 1, "settings", what);

    if (kind == StageKind::Resolver) {
      const std::vector<std::string> functions = keys_of(L, 1, "functions", what);
      if (functions.size() > kMaxFunctions)
        throw InputError(d.where, what + " declares " + std::to_string(functions.size()) +
                                      " interaction functions; a resolver may declare at most " +
                                      std::to_string(kMaxFunctions));
      for (const auto& f : functions) {
        lua_getfield(L, 1, "functions");
        lua_getfield(L, -1, f.c_str());
        FunctionDecl fd{f, {}};
        if (!lua_istable(L, -1))
          throw InputError(d.where,
                           what + ": interaction function '" + f +
                               "' must list its arguments after the object, e.g. {\"number\"}");
        const int n = int(lua_objlen(L, -1));
        for (int i = 1; i <= n; ++i) {
          lua_rawgeti(L, -1, i);
          const std::string k = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "";
          lua_pop(L, 1);
          if (k == "number")
            fd.args.push_back(ArgKind::Number);
          else if (k == "object")
            fd.args.push_back(ArgKind::Object);
          else if (k == "vec3")
            fd.args.push_back(ArgKind::Vec3);
          else
            throw InputError(d.where, what + ": argument " + std::to_string(i) + " of '" + f +
                                          "' must be \"number\", \"object\" or \"vec3\"");
        }
        lua_pop(L, 2);
        if (fd.args.size() > 4)
          throw InputError(d.where,
                           what + ": '" + f + "' takes at most 4 arguments after the object");
        d.functions.push_back(std::move(fd));
      }
    }
    if (kind == StageKind::Derived) {
      for (const auto& o : keys_of(L, 1, "provides", what)) {
        lua_getfield(L, 1, "provides");
        lua_getfield(L, -1, o.c_str());
        const std::string k = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "";
        lua_pop(L, 2);
        if (k != "number" && k != "vec3")
          throw InputError(d.where, what + ": output '" + o + "' must be \"number\" or \"vec3\"");
        d.provides.push_back({o, k == "vec3" ? PropertyKind::Vec3 : PropertyKind::Number});
      }
      if (d.provides.empty())
        throw InputError(
            d.where,
            what + " provides nothing: list its outputs, e.g. provides = { charge = \"number\" }");
    }
    const char* body = kind == StageKind::Resolver  ? "advance"
                       : kind == StageKind::Derived ? "update"
                                                    : "apply";
    lua_getfield(L, 1, body);
    if (!lua_isfunction(L, -1))
      throw InputError(d.where, what + " needs its function: " + body + " = function(w" +
                                    (kind == StageKind::Resolver ? ", dt" : "") + ") ... end");
    lua_pop(L, 1);
    if (kind == StageKind::Resolver) {
      lua_getfield(L, 1, "build");
      if (!lua_isnil(L, -1) && !lua_isfunction(L, -1))
        throw InputError(d.where, what + ": 'build' must be a function");
      lua_pop(L, 1);
    }
    for (const auto& s : program.stages)
      if (s.info.name == d.info.name) throw InputError(d.where, what + " is defined twice");
    lua_pushvalue(L, 1);
    d.def_ref = luaL_ref(L, LUA_REGISTRYINDEX);
    program.stages.push_back(std::move(d));
  }

  void on(lua_State* L) {
    const std::string type = luaL_checkstring(L, 1);
    if (type.empty())
      throw InputError(here(L), "mod.on needs an event type, or \"*\" for every event");
    luaL_checktype(L, 2, LUA_TFUNCTION);
    lua_pushvalue(L, 2);
    program.handlers.emplace_back(type, luaL_ref(L, LUA_REGISTRYINDEX));
  }
};

namespace {

int mod_property(lua_State* L) {
  return catch_exceptions(L, [&] { return Collector::from(L)->property(L), 0; });
}
int mod_resolver(lua_State* L) {
  return catch_exceptions(L, [&] { return Collector::from(L)->stage(L, StageKind::Resolver), 0; });
}
int mod_derived(lua_State* L) {
  return catch_exceptions(L, [&] { return Collector::from(L)->stage(L, StageKind::Derived), 0; });
}
int mod_interaction(lua_State* L) {
  return catch_exceptions(L,
                          [&] { return Collector::from(L)->stage(L, StageKind::Interaction), 0; });
}
int mod_on(lua_State* L) {
  return catch_exceptions(L, [&] { return Collector::from(L)->on(L), 0; });
}

}  // namespace

// --- ModState -----------------------------------------------------------------------

ModState::ModState(Manifest manifest, std::vector<fs::path> search_path, ModBudget budget, Log log)
    : manifest_(std::move(manifest)),
      search_path_(std::move(search_path)),
      budget_(budget),
      log_(std::move(log)) {
  make_state();
}

ModState::~ModState() {
  if (program_) release(*program_);
}

std::string ModState::runtime_file() const {
  return manifest_.runtime;
}

void ModState::make_state() {
  host_ = std::make_unique<LuaHost>(HostOptions{budget_.memory_bytes, 0});
  lua_State* L = host_->state();
  StackGuard guard(L);
  // Pattern matching is paid in ticks (lua_patterns.hpp), and one call over
  // its allowance stops the mod as a runaway loop does.
  host_->set_work_account(
      WorkAccount{[this](lua_State* L, std::uint64_t steps) {
                    step_ticks_ += steps / kPatternStepsPerTick;
                    lua_pushlightuserdata(L, this);
                    lua_pushcclosure(L, &ModState::over_budget, 1);
                    lua_call(L, 0, 0);
                  },
                  [this](lua_State* L, const std::string& why) { stop(L, why); }});

  abi_budget_ = new (lua_newuserdata(L, sizeof(abi::Budget))) abi::Budget{};
  host_->memory().zero_on_refusal(&abi_budget_->ticks);  // the userdata lives as long as L
  lua_pushvalue(L, -1);
  budget_ud_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
  const int budget_ud = lua_gettop(L);

  // The prelude is host code: no ticks, the state's own globals, and the FFI.
  // The FFI is opened before the prelude is parsed: its 0ULL literals make
  // LuaJIT's lexer open it on demand otherwise, and a second luaopen_ffi
  // would replace that first type state and leak it (found by the fuzzers).
  lua_pushcfunction(L, luaopen_ffi);
  lua_call(L, 0, 1);
  const int ffi = lua_gettop(L);
  const std::string_view src = kStagePreludeSource;
  if (luaL_loadbufferx(L, src.data(), src.size(), "=alloy.prelude", "t") != 0)
    throw std::runtime_error(std::string("the stage prelude does not compile: ") +
                             lua_tostring(L, -1));
  const int chunk = lua_gettop(L);
  lua_pushvalue(L, ffi);
  lua_pushlightuserdata(L, const_cast<abi::Api*>(&stage_api()));
  lua_pushvalue(L, budget_ud);
  lua_pushlightuserdata(L, this);
  lua_pushcclosure(L, &ModState::over_budget, 1);
  push_stage_host_functions(L);
  lua_pushstring(L, abi::kCdef);
  lua_pushstring(L, manifest_.name.c_str());
  (void)chunk;
  host_->call(7, 1, ErrorLocation{"alloy.prelude", 0, ""});
  prelude_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);

  lua_rawgeti(L, LUA_REGISTRYINDEX, prelude_ref_);
  lua_getfield(L, -1, "tick");
  if (budget_.ticks) host_->use_budget_ticks(-1);
  lua_pop(L, 1);
  // This state's string metatable is the mod's own: its methods ("x"):find(p)
  // get the guarded pattern functions too (the metatable stays hidden).
  lua_getfield(L, -1, "string");
  const int guarded = lua_gettop(L);
  lua_pushliteral(L, "");
  lua_getmetatable(L, -1);
  lua_getfield(L, -1, "__index");  // the real string table
  for (lua_pushnil(L); lua_next(L, guarded); lua_pop(L, 1)) {
    lua_pushvalue(L, -2);
    lua_pushvalue(L, -2);
    lua_rawset(L, -5);
  }
  lua_pop(L, 5);

  lua_newtable(L);
  state_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
}

int ModState::prelude_ref(const char* fn) const {
  lua_State* L = host_->state();
  auto& cache = prelude_fns_;  // looked up once each
  for (const auto& [name, ref] : cache)
    if (name == fn) return ref;
  lua_rawgeti(L, LUA_REGISTRYINDEX, prelude_ref_);
  lua_getfield(L, -1, fn);
  const int ref = luaL_ref(L, LUA_REGISTRYINDEX);
  lua_pop(L, 1);
  cache.emplace_back(fn, ref);
  return ref;
}

void ModState::push_state() {
  lua_rawgeti(host_->state(), LUA_REGISTRYINDEX, state_ref_);
}

void ModState::resume() {
  if (!stopped_) return;
  saved_reason_ = stop_reason_;
  saved_message_ = stop_message_;
  stopped_ = false;
  stop_reported = false;
  stop_event_sent = false;
  stop_reason_.clear();
  stop_message_.clear();
  abi_budget_->stopped = 0;
  lua_State* L = host_->state();
  luaL_unref(L, LUA_REGISTRYINDEX, state_ref_);
  lua_newtable(L);
  state_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
  for (LuaStage* s : stages_) s->reset_state();
  lua_gc(L, LUA_GCCOLLECT, 0);
}

void ModState::restop() {
  stopped_ = true;
  stop_reported = true;
  stop_event_sent = true;
  stop_reason_ = saved_reason_;
  stop_message_ = saved_message_;
  abi_budget_->stopped = 1;
}

void ModState::install_environment(lua_State* L, int env, const std::string& mod, int box_ref,
                                   Collector* c) {
  env = abs_index(L, env);
  push_alloy_api(L);
  lua_setfield(L, env, "alloy");
  lua_rawgeti(L, LUA_REGISTRYINDEX, prelude_ref_);
  const int m = lua_gettop(L);
  for (const char* name : {"pairs", "vec3", "quat"}) {
    lua_getfield(L, m, name);
    lua_setfield(L, env, name);
  }
  lua_getfield(L, env, "string");  // the environment's own copy: guarded patterns
  lua_getfield(L, m, "string");
  for (lua_pushnil(L); lua_next(L, -2); lua_pop(L, 1)) {
    lua_pushvalue(L, -2);
    lua_pushvalue(L, -2);
    lua_rawset(L, -6);
  }
  lua_pop(L, 2);
  lua_getfield(L, env, "math");  // the environment's own copy
  lua_getfield(L, m, "random");
  lua_setfield(L, -2, "random");
  lua_getfield(L, m, "randomseed");
  lua_setfield(L, -2, "randomseed");
  lua_pop(L, 2);
  lua_pushlightuserdata(L, this);
  lua_pushcclosure(L, &ModState::print_fn, 1);
  lua_setfield(L, env, "print");
  if (!mod.empty() || !c) return;  // a dependency's files: no `mod` table

  lua_createtable(L, 0, 8);
  lua_pushstring(L, manifest_.name.c_str());
  lua_setfield(L, -2, "name");
  lua_pushstring(L, manifest_.version.c_str());
  lua_setfield(L, -2, "version");
  const luaL_Reg fns[] = {{"property", mod_property},
                          {"resolver", mod_resolver},
                          {"derived", mod_derived},
                          {"interaction", mod_interaction},
                          {"on", mod_on}};
  for (const auto& f : fns) {
    lua_rawgeti(L, LUA_REGISTRYINDEX, box_ref);
    lua_pushcclosure(L, f.func, 1);
    lua_setfield(L, -2, f.name);
  }
  lua_pushvalue(L, -1);
  if (c->mod_ref != -2) luaL_unref(L, LUA_REGISTRYINDEX, c->mod_ref);
  c->mod_ref = luaL_ref(L, LUA_REGISTRYINDEX);
  lua_setfield(L, env, "mod");
}

int ModState::print_fn(lua_State* L) {
  auto* self = static_cast<ModState*>(lua_touserdata(L, lua_upvalueindex(1)));
  if (self->stopped_) self->stop(L, "");  // a stopped mod prints nothing, even inside a pcall
  // Room left in the step's and the run's budgets. The line is built only up
  // to it: a print of a huge string (or of thousands of arguments) copies no
  // more than that into the host; the rest is only measured.
  const ModBudget& b = self->budget_;
  const auto left = [](std::uint64_t limit, std::uint64_t used) {
    return used >= limit ? std::uint64_t(0) : limit - used;
  };
  const std::uint64_t step_left = left(b.print_bytes_per_step, self->step_out_.print_bytes);
  const std::uint64_t run_left = left(b.print_bytes_per_run, self->run_out_.print_bytes);
  const std::uint64_t room = std::min(step_left, run_left);
  std::string line;
  const std::uint64_t total = print_line(L, room, line);
  if (total <= room) {
    self->step_out_.print_bytes += total;
    self->run_out_.print_bytes += total;
    self->log(line);
    return 0;
  }
  // Over: what fits is printed, then one line says how much was dropped.
  const std::uint64_t kept = line.size();
  self->step_out_.print_bytes += kept;
  self->run_out_.print_bytes += kept;
  self->step_out_.print_dropped += total - kept;
  self->run_out_.print_dropped += total - kept;
  if (!line.empty()) self->log(line);
  self->log("... (" + std::to_string(total - kept) + " more bytes dropped)");
  std::string().swap(line);  // stop() unwinds past this frame
  const bool per_run = run_left < step_left;
  self->stop(L, per_run
                    ? self->over("printed", b.print_bytes_per_run, "print_bytes_per_run", true)
                    : self->over("printed", b.print_bytes_per_step, "print_bytes_per_step", false));
}

std::string ModState::over(const char* what, std::uint64_t limit, const char* name, bool per_run,
                           const char* unit) const {
  return std::string("it ") + what + " more than " +
         (*unit ? std::to_string(limit) + unit : bytes_text(limit)) +
         (per_run    ? " since it was loaded"
          : loading_ ? " while loading"
                     : " in one step") +
         " (its budget " + name + ")";
}

void ModState::mark_stopped(const std::string& why) {
  if (!stopped_) {
    stopped_ = true;
    stop_message_ = "mod '" + manifest_.name + "' stopped: " + why;
    stop_reason_ = stop_message_;
    stop_unplaced_ = true;
  }
  // The next tick of the mod's code fails again (over_budget): a pcall
  // around the refused call cannot keep the mod going.
  abi_budget_->stopped = 1;
  abi_budget_->ticks = 0;
  granted_ = 0;
}

void ModState::place_stop(const ErrorLocation& where) {
  if (!stopped_ || !stop_unplaced_ || where.file.empty()) return;
  stop_unplaced_ = false;
  stop_reason_ = InputError::format(ErrorLocation{where.file, where.line, ""}, stop_message_);
}

std::string ModState::count_event(std::size_t bytes) {
  if (stopped_) return stop_message_;
  const ModBudget& b = budget_;
  std::string why;
  if (step_out_.events + 1 > b.events_per_step)
    why = over("emitted", b.events_per_step, "events_per_step", false, " events");
  else if (run_out_.events + 1 > b.events_per_run)
    why = over("emitted", b.events_per_run, "events_per_run", true, " events");
  else if (step_out_.event_bytes + bytes > b.event_bytes_per_step)
    why = over("emitted events of", b.event_bytes_per_step, "event_bytes_per_step", false);
  else if (run_out_.event_bytes + bytes > b.event_bytes_per_run)
    why = over("emitted events of", b.event_bytes_per_run, "event_bytes_per_run", true);
  if (!why.empty()) {
    mark_stopped(why + "; an event of " + std::to_string(bytes) + " bytes was refused");
    return stop_message_;
  }
  ++step_out_.events;
  ++run_out_.events;
  step_out_.event_bytes += bytes;
  run_out_.event_bytes += bytes;
  return "";
}

std::string ModState::count_energy_report() {
  if (stopped_) return stop_message_;
  if (step_out_.energy_reports + 1 > budget_.energy_reports_per_step) {
    mark_stopped(over("made", budget_.energy_reports_per_step, "energy_reports_per_step", false,
                      " energy reports") +
                 "; the report was refused");
    return stop_message_;
  }
  ++step_out_.energy_reports;
  ++run_out_.energy_reports;
  return "";
}

std::string ModState::may_queue(std::size_t bytes_in_call, std::uint64_t commands_in_call) {
  if (stopped_) return stop_message_;
  if (step_out_.commands + commands_in_call > budget_.commands_per_step) {
    mark_stopped(
        over("queued", budget_.commands_per_step, "commands_per_step", false, " commands") +
        "; the commands of this call were refused");
    return stop_message_;
  }
  if (step_out_.command_bytes + bytes_in_call > budget_.command_bytes_per_step) {
    mark_stopped(over("queued commands taking", budget_.command_bytes_per_step,
                      "command_bytes_per_step", false) +
                 "; the commands of this call were refused");
    return stop_message_;
  }
  return "";
}

std::string ModState::count_commands(std::uint64_t n, std::size_t bytes) {
  if (std::string why = may_queue(bytes, n); !why.empty()) return why;
  step_out_.commands += n;
  run_out_.commands += n;
  step_out_.command_bytes += bytes;
  run_out_.command_bytes += bytes;
  return "";
}

InputError ModState::bounded(const InputError& e) const {
  const std::size_t limit = std::max<std::size_t>(budget_.error_bytes, 64);
  const ErrorLocation& w = e.where();
  if (e.bare().size() <= limit && w.file.size() <= 256 && w.object.size() <= 256) return e;
  return InputError(ErrorLocation{cut(w.file, 256), w.line, cut(w.object, 256)},
                    cut(e.bare(), limit));
}

std::unique_ptr<Program> ModState::load_program() {
  auto prog = std::make_unique<Program>();
  const std::string runtime = runtime_file();
  if (runtime.empty()) return prog;
  run_out_ = Output{};  // a load or reload starts a new run of the output budgets
  lua_State* L = host_->state();
  StackGuard guard(L);

  const fs::path file = manifest_.folder / runtime;
  const std::string display = display_path(file);
  if (!fs::is_regular_file(file))
    throw InputError(ErrorLocation{manifest_.file, 0, ""},
                     "mod '" + manifest_.name + "' names its runtime file '" + runtime +
                         "', but there is no file " + display);
  Collector c{*this, *prog};
  auto** box = static_cast<Collector**>(lua_newuserdata(L, sizeof(Collector*)));
  *box = &c;
  const int box_ref = luaL_ref(L, LUA_REGISTRYINDEX);
  auto loader = std::make_shared<ModLoader>(*host_, search_path_,
                                            [&](lua_State* L, int env, const std::string& mod) {
                                              install_environment(L, env, mod, box_ref, &c);
                                            });
  loader->set_scene_mod(manifest_);

  const bool was_stopped = stopped_;
  auto cleanup = [&] {
    *box = nullptr;  // the mod's functions refuse to define anything after this
    luaL_unref(L, LUA_REGISTRYINDEX, box_ref);
    if (c.mod_ref != -2) luaL_unref(L, LUA_REGISTRYINDEX, c.mod_ref);
  };
  try {
    host_->load_file(contained_file(manifest_.name, manifest_.folder, file,
                                    ErrorLocation{manifest_.file, 0, ""}),
                     display);
    loader->add_scene_file(display);
    loader->push_environment(manifest_.name);
    lua_setfenv(L, -2);
    begin_loading();
    try {
      host_->call(0, 0, ErrorLocation{display, 0, ""});
    } catch (const InputError& e) {
      end_call();
      place_stop(e.where());
      throw bounded(e);
    } catch (...) {
      end_call();
      throw;
    }
    end_call();
    if (stopped_ && !was_stopped) throw InputError(stop_reason_);  // stopped inside a pcall
    // The hooks the file set on `mod`.
    lua_rawgeti(L, LUA_REGISTRYINDEX, c.mod_ref);
    for (auto [key, ref] : {std::pair<const char*, int*>{"on_load", &prog->on_load},
                            {"on_reload", &prog->on_reload},
                            {"on_unload", &prog->on_unload},
                            {"on_migrate", &prog->on_migrate}}) {
      lua_getfield(L, -1, key);
      if (lua_isfunction(L, -1))
        *ref = luaL_ref(L, LUA_REGISTRYINDEX);
      else if (!lua_isnil(L, -1))
        throw InputError(ErrorLocation{display, 0, ""},
                         std::string("mod.") + key + " must be a function");
      else
        lua_pop(L, 1);
    }
    lua_pop(L, 1);
  } catch (...) {
    cleanup();
    release(*prog);
    if (!was_stopped) {
      stopped_ = false;
      stop_reported = false;
      stop_event_sent = false;
      abi_budget_->stopped = 0;
      stop_reason_.clear();
    }
    throw;
  }
  cleanup();
  for (const auto& [f, mod] : loader->loaded_files())
    if (mod.empty()) prog->files.push_back(f);
  std::sort(prog->files.begin(), prog->files.end());
  // Later requires (inside a stage) make environments without a `mod` table.
  loader->set_decorate([this](lua_State* L, int env, const std::string& mod) {
    install_environment(L, env, mod, -2, nullptr);
  });
  prog->loader = std::move(loader);
  return prog;
}

void ModState::release(Program& p) {
  lua_State* L = host_->state();
  for (auto& s : p.stages) luaL_unref(L, LUA_REGISTRYINDEX, s.def_ref), s.def_ref = -2;
  for (auto& [type, ref] : p.handlers) luaL_unref(L, LUA_REGISTRYINDEX, ref), ref = -2;
  for (int* r : {&p.on_load, &p.on_reload, &p.on_unload, &p.on_migrate})
    if (*r != -2) luaL_unref(L, LUA_REGISTRYINDEX, *r), *r = -2;
  p.loader.reset();
}

std::unique_ptr<Program> ModState::set_program(std::unique_ptr<Program> p) {
  std::swap(program_, p);
  // Live stages whose declarations did not change take the new functions.
  for (LuaStage* s : stages_)
    if (const StageDecl* d = program_->stage(s->name()); d && p) {
      const StageDecl* old = p->stage(s->name());
      if (old && old->same_shape(*d)) s->rebind(*d);
    }
  return p;
}

void ModState::call_hook(int ref, const char* what) {
  if (ref == -2) return;
  lua_State* L = host_->state();
  StackGuard guard(L);
  lua_rawgeti(L, LUA_REGISTRYINDEX, ref);
  push_state();
  begin_loading();
  try {
    host_->call(1, 0, ErrorLocation{display_path(manifest_.folder / runtime_file()), 0, ""});
  } catch (const InputError& e) {
    end_call();
    place_stop(e.where());
    const InputError b = bounded(e);
    throw InputError(b.where(), std::string(what) + ": " + b.bare());
  }
  end_call();
  if (stopped_) throw InputError(stop_reason_);
}

std::vector<std::byte> ModState::save_state() {
  lua_State* L = host_->state();
  StackGuard guard(L);
  lua_rawgeti(L, LUA_REGISTRYINDEX, prelude_ref("cdata_parts"));
  push_state();
  return encode_state(L, -1, manifest_.name, state_limits(), -2);
}

void ModState::call_state_hook(int fn, const char* what, int state_ref, const std::string* from) {
  lua_State* L = host_->state();
  const bool was_stopped = stopped_;
  const std::string in = "mod '" + manifest_.name + "': " + what + " failed: ";
  if (was_stopped)
    throw InputError(in + "the mod is stopped (" + stop_message_ + "); reload it first");
  // A stop in the hook is undone: the restore that called it is refused as a
  // whole, and the mod goes on as it was.
  auto unstop = [&] {
    if (was_stopped || !stopped_) return;
    stopped_ = false;
    stop_reported = false;
    stop_event_sent = false;
    abi_budget_->stopped = 0;
    stop_reason_.clear();
    stop_message_.clear();
    stop_unplaced_ = false;
  };
  lua_rawgeti(L, LUA_REGISTRYINDEX, fn);
  if (from) lua_pushlstring(L, from->data(), from->size());
  lua_rawgeti(L, LUA_REGISTRYINDEX, state_ref);
  begin_loading();
  try {
    host_->call(from ? 2 : 1, 1,
                ErrorLocation{display_path(manifest_.folder / runtime_file()), 0, ""});
  } catch (const InputError& e) {
    end_call();
    place_stop(e.where());
    const InputError b = bounded(e);
    unstop();
    throw InputError(b.where(), in + b.bare());
  }
  end_call();
  if (stopped_ && !was_stopped) {
    const std::string why = stop_message_;
    unstop();
    lua_pop(L, 1);
    throw InputError(in + why);
  }
}

int ModState::prepare_state(const std::vector<std::byte>& bytes, const std::string& from,
                            bool* migrated) {
  lua_State* L = host_->state();
  StackGuard guard(L);
  const StateLimits limits = state_limits();
  check_state(bytes, manifest_.name, limits);
  std::string error;
  lua_rawgeti(L, LUA_REGISTRYINDEX, prelude_ref("cdata_make"));
  const bool decoded = decode_state(L, bytes, &error, -1);
  lua_remove(L, decoded ? -2 : -1);
  if (!decoded)
    throw InputError("mod '" + manifest_.name + "': its saved state of " +
                     std::to_string(bytes.size()) +
                     " bytes does not fit in its Lua state: " + error);
  int ref = luaL_ref(L, LUA_REGISTRYINDEX);
  if (migrated) *migrated = false;
  if (from == manifest_.version || !program_ || program_->on_migrate == -2) return ref;
  const std::string what =
      "on_migrate(\"" + from + "\", state) (to version " + manifest_.version + ")";
  try {
    call_state_hook(program_->on_migrate, what.c_str(), ref, &from);
    if (!lua_isnil(L, -1) && !lua_istable(L, -1))
      throw InputError("mod '" + manifest_.name + "': " + what + " returned a " +
                       luaL_typename(L, -1) + "; return the state table, or nothing");
    if (lua_istable(L, -1)) {
      luaL_unref(L, LUA_REGISTRYINDEX, ref);
      ref = luaL_ref(L, LUA_REGISTRYINDEX);
    }
    lua_rawgeti(L, LUA_REGISTRYINDEX, prelude_ref("cdata_parts"));
    lua_rawgeti(L, LUA_REGISTRYINDEX, ref);
    try {
      (void)encode_state(L, -1, manifest_.name, limits, -2);  // what it made must be a state
    } catch (const InputError& e) {
      throw InputError("after " + what + ": " + e.bare());
    }
  } catch (...) {
    luaL_unref(L, LUA_REGISTRYINDEX, ref);
    throw;
  }
  if (migrated) *migrated = true;
  return ref;
}

int ModState::prepare_fresh_state() {
  lua_State* L = host_->state();
  StackGuard guard(L);
  lua_newtable(L);
  const int ref = luaL_ref(L, LUA_REGISTRYINDEX);
  if (!program_ || program_->on_load == -2) return ref;
  try {
    call_state_hook(program_->on_load, "on_load(state) (the snapshot holds no state of the mod)",
                    ref, nullptr);
  } catch (...) {
    luaL_unref(L, LUA_REGISTRYINDEX, ref);
    throw;
  }
  return ref;
}

void ModState::commit_state(int ref) {
  lua_State* L = host_->state();
  luaL_unref(L, LUA_REGISTRYINDEX, state_ref_);
  state_ref_ = ref;
  for (LuaStage* s : stages_) s->reset_state();
}

void ModState::drop_state(int ref) {
  luaL_unref(host_->state(), LUA_REGISTRYINDEX, ref);
}

void ModState::detach(LuaStage* s) {
  std::erase(stages_, s);
}

// --- budgets ------------------------------------------------------------------------

void ModState::begin_call(std::uint64_t step) {
  if (step != step_) {
    step_ = step;
    step_ticks_ = 0;
    step_seconds_ = 0;
    step_out_ = Output{};
  }
  tick_limit_ = budget_.ticks_per_step;
  call_start_ = std::chrono::steady_clock::now();
  deadline_ =
      call_start_ +
      std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(std::max(0.0, budget_.seconds_per_step - step_seconds_)));
  granted_ = stopped_ ? 0 : kQuantum;
  abi_budget_->ticks = std::int16_t(granted_);
  abi_budget_->stopped = stopped_ ? 1 : 0;
  refusals_seen_ = host_->memory().refusals();
}

void ModState::begin_loading() {
  step_ = ~0ull - 1;  // a call outside the steps: its own account
  step_ticks_ = 0;
  step_seconds_ = 0;
  step_out_ = Output{};
  tick_limit_ = budget_.ticks_to_load;
  call_start_ = std::chrono::steady_clock::now();
  deadline_ = call_start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(budget_.seconds_to_load));
  granted_ = stopped_ ? 0 : kQuantum;
  abi_budget_->ticks = std::int16_t(granted_);
  refusals_seen_ = host_->memory().refusals();
  loading_ = true;
}

void ModState::charge() {
  const std::int64_t spent = std::int64_t(granted_) - std::int64_t(abi_budget_->ticks);
  if (spent > 0) step_ticks_ += std::uint64_t(spent);
  granted_ = std::int32_t(abi_budget_->ticks);
}

void ModState::end_call() {
  charge();
  stop_if_refused(nullptr);  // a refusal caught by the call's last pcall
  step_seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - call_start_).count();
  if (loading_) {
    loading_ = false;
    step_ = ~0ull;
  }
}

void ModState::stop(lua_State* L, const std::string& why) {
  const ErrorLocation where = mod_location(L);
  place_stop(where);
  if (!stopped_) {
    stopped_ = true;
    stop_message_ = "mod '" + manifest_.name + "' stopped: " + why;
    stop_reason_ = InputError::format(where, stop_message_);
  }
  abi_budget_->stopped = 1;
  abi_budget_->ticks = 0;
  granted_ = 0;
  push_error_table(L, where, stop_message_);
  raise_error_table(L);
}

void ModState::stop_if_refused(lua_State* L) {
  if (stopped_ || host_->memory().refusals() == refusals_seen_) return;
  const std::string why = "it ran out of its memory budget of " +
                          std::to_string(budget_.memory_bytes >> 20) +
                          " MiB (an allocation was refused; a pcall does not undo that)";
  if (L) stop(L, why);  // raises
  stopped_ = true;
  stop_message_ = "mod '" + manifest_.name + "' stopped: " + why;
  stop_reason_ = InputError::format(
      ErrorLocation{display_path(manifest_.folder / runtime_file()), 0, ""}, stop_message_);
  abi_budget_->stopped = 1;
  abi_budget_->ticks = 0;
}

int ModState::over_budget(lua_State* L) {
  auto* self = static_cast<ModState*>(lua_touserdata(L, lua_upvalueindex(1)));
  self->charge();
  // Already stopped: fail again, so that a pcall around a loop cannot
  // swallow the stop and loop on.
  if (self->stopped_) self->stop(L, "");
  // The allocator refused (and zeroed the ticks to get here): the mod stops
  // even if a pcall caught the "not enough memory" error.
  self->stop_if_refused(L);
  if (self->step_ticks_ > self->tick_limit_)
    self->stop(L, "it ran more than " + millions(self->tick_limit_) +
                      " ticks (loop iterations and calls) " +
                      (self->loading_ ? "while loading" : "in one step") + " (a runaway loop?)");
  if (std::chrono::steady_clock::now() > self->deadline_) {
    char buf[64];
    std::snprintf(
        buf, sizeof buf, "%g ms",
        1000 * (self->loading_ ? self->budget_.seconds_to_load : self->budget_.seconds_per_step));
    self->stop(L, std::string("it ran longer than ") + buf +
                      (self->loading_ ? " while loading" : " in one step"));
  }
  const std::size_t limit = self->budget_.memory_bytes;
  if (limit > 0 && self->host_->memory().used() > limit / 10 * 9) {
    lua_gc(L, LUA_GCCOLLECT, 0);
    if (self->host_->memory().used() > limit / 10 * 9)
      self->stop(L, "it holds more than 90% of its memory budget of " +
                        std::to_string(limit >> 20) + " MiB (an allocation bomb?)");
  }
  self->granted_ = kQuantum;
  self->abi_budget_->ticks = std::int16_t(kQuantum);
  return 0;
}

bool ModState::run_stage(int record_ref, const char* phase, double dt, double time,
                         std::uint64_t step, const ErrorLocation& fallback, InputError* error) {
  lua_State* L = host_->state();
  StackGuard guard(L);
  if (run_ref_ == -2) run_ref_ = prelude_ref("run");
  lua_rawgeti(L, LUA_REGISTRYINDEX, run_ref_);
  lua_rawgeti(L, LUA_REGISTRYINDEX, record_ref);
  int phase_ref = -2;
  for (const auto& [p, ref] : phases_)
    if (p == phase) phase_ref = ref;
  if (phase_ref == -2) {
    lua_pushstring(L, phase);
    phase_ref = luaL_ref(L, LUA_REGISTRYINDEX);
    phases_.emplace_back(phase, phase_ref);
  }
  lua_rawgeti(L, LUA_REGISTRYINDEX, phase_ref);
  lua_pushnumber(L, dt);
  lua_pushnumber(L, time);
  lua_pushnumber(L, double(step));
  begin_call(step);
  try {
    host_->call(5, 0, fallback);
  } catch (const InputError& raised) {
    const bool was_stopped = stopped_;
    end_call();  // stops the mod if the allocator refused: out of memory, not just wrong
    place_stop(raised.where());
    const InputError e = bounded(raised);
    if (stopped_ && !was_stopped) stop_reason_ = InputError::format(e.where(), stop_message_);
    *error = e;
    return false;
  }
  end_call();
  if (stopped_) {
    place_stop(fallback);  // stopped where no line was known, and a pcall swallowed the error
    *error = InputError(stop_reason_);
    return false;
  }
  return true;
}

}  // namespace alloy::lua
