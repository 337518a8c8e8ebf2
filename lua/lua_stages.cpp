#include "lua/lua_stages.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <lua.hpp>
#include <utility>
#include <variant>

#include "lua/lua_bridge.hpp"
#include "lua/native_bindings.hpp"
#include "runtime/contact_set.hpp"

namespace alloy::lua {

namespace {

const abi::Api kApi = {
    &LuaStage::api_fetch,    &LuaStage::api_set_scalar, &LuaStage::api_set_vec3,
    &LuaStage::api_set_quat, &LuaStage::api_has,        &LuaStage::api_grow,
    &LuaStage::api_commands, &LuaStage::api_contacts,   &LuaStage::api_bulk,
};

constexpr std::size_t kCommandBuffer = 8192;  // doubles: grows when a call queues more

abi::ColumnKind abi_kind(PropertyKind k) {
  switch (k) {
    case PropertyKind::Number:
      return abi::kNumber;
    case PropertyKind::Integer:
      return abi::kInteger;
    case PropertyKind::Bool:
      return abi::kBool;
    case PropertyKind::Vec3:
      return abi::kVec3;
    case PropertyKind::Quat:
      return abi::kQuat;
    case PropertyKind::Enum:
      return abi::kEnum;
    case PropertyKind::Ref:
      return abi::kRef;
    default:
      return abi::kOther;
  }
}

const char* kind_name(StageKind k) {
  switch (k) {
    case StageKind::Resolver:
      return "resolver";
    case StageKind::Derived:
      return "derived";
    case StageKind::Interaction:
      return "interaction";
  }
  return "?";
}

LuaStage* stage_of(lua_State* L) {
  if (lua_type(L, 1) != LUA_TLIGHTUSERDATA) luaL_error(L, "bad stage handle");
  return static_cast<LuaStage*>(lua_touserdata(L, 1));
}

void push_string_list(lua_State* L, const std::vector<std::string>& v) {
  lua_createtable(L, int(v.size()), 0);
  for (std::size_t i = 0; i < v.size(); ++i) {
    lua_pushlstring(L, v[i].data(), v[i].size());
    lua_rawseti(L, -2, int(i) + 1);
  }
}

void push_functions(lua_State* L, const std::vector<FunctionDecl>& fns) {
  lua_createtable(L, int(fns.size()), 0);
  for (std::size_t i = 0; i < fns.size(); ++i) {
    lua_createtable(L, 0, 3);
    lua_pushstring(L, fns[i].name.c_str());
    lua_setfield(L, -2, "name");
    lua_pushinteger(L, lua_Integer(i));
    lua_setfield(L, -2, "index");
    lua_createtable(L, int(fns[i].args.size()), 0);
    for (std::size_t a = 0; a < fns[i].args.size(); ++a) {
      const std::string_view k = to_string(fns[i].args[a]);
      lua_pushlstring(L, k.data(), k.size());
      lua_rawseti(L, -2, int(a) + 1);
    }
    lua_setfield(L, -2, "kinds");
    lua_rawseti(L, -2, int(i) + 1);
  }
}

int widths(const std::vector<ArgKind>& args) {
  int n = 0;
  for (ArgKind a : args) n += width(a);
  return n;
}

std::string number_text(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// Why `v` may not be stored in a property of `def` ("" if it may).
std::string bounds_problem(const PropertyDef& def, double v) {
  if (!std::isfinite(v)) return "must be finite, got " + number_text(v);
  if (def.min && (def.min_exclusive ? !(v > *def.min) : !(v >= *def.min)))
    return std::string("must be ") + (def.min_exclusive ? "above " : "at least ") +
           number_text(*def.min) + ", got " + number_text(v);
  if (def.max && !(v <= *def.max))
    return "must be at most " + number_text(*def.max) + ", got " + number_text(v);
  return "";
}

}  // namespace

const abi::Api& stage_api() {
  return kApi;
}

void push_stage_host_functions(lua_State* L) {
  const luaL_Reg fns[] = {
      {"last_error", &LuaStage::host_last_error},
      {"name", &LuaStage::host_name},
      {"find", &LuaStage::host_find},
      {"alive", &LuaStage::host_alive},
      {"emit", &LuaStage::host_emit},
      {"slow_get", &LuaStage::host_slow_get},
      {"slow_set", &LuaStage::host_slow_set},
      {"energy", &LuaStage::host_energy},
  };
  lua_createtable(L, 0, int(std::size(fns)));
  for (const auto& f : fns) {
    lua_pushcfunction(L, f.func);
    lua_setfield(L, -2, f.name);
  }
}

// --- LuaStage ---------------------------------------------------------------------

LuaStage::LuaStage(std::shared_ptr<ModState> mod, const StageDecl& decl, PluginContext& ctx)
    : mod_(std::move(mod)),
      decl_name_(decl.info.name),
      target_(decl.info.target),
      kind_(decl.info.kind),
      where_(decl.where),
      world_(ctx.world()) {
  instance_ = ctx.area().empty() ? decl_name_ : decl_name_ + "@" + ctx.area();
  const PropertyRegistry& props = world_.properties();
  auto add_property = [&](const std::string& name, bool writable) {
    const PropertyId id = props.id(name);
    for (auto& s : sources_)
      if (s.what == Source::Property && s.property == id) {
        s.writable = s.writable || writable;
        return;
      }
    sources_.push_back(Source{Source::Property, id, props.def(id).kind, writable});
    column_names_.push_back(name);
  };
  for (const auto& p : decl.info.reads) add_property(p, false);
  if (kind_ == StageKind::Resolver)
    for (const auto& p : decl.info.writes) add_property(p, true);
  for (const auto& p : decl.info.needs) add_property(p, false);
  for (const auto& d : decl.info.derived) {
    if (native_derived_readable(ctx.world().plugins(), d)) {  // a contact set
      collisions_ = &ctx.dependency<ContactSet>(d);
      impulses_ = collisions_->demand_impulses();
      continue;
    }
    const auto& set = ctx.dependency<LuaDerivedSet>(d);
    for (std::size_t o = 0; o < set.outputs().size(); ++o) {
      sources_.push_back(
          Source{Source::DerivedInput, kNoProperty, set.outputs()[o].kind, false, int(o), &set});
      column_names_.push_back(set.outputs()[o].name);
    }
  }
  if (kind_ == StageKind::Derived)
    for (std::size_t o = 0; o < decl.provides.size(); ++o) {
      sources_.push_back(Source{Source::Output, kNoProperty, decl.provides[o].kind, true, int(o)});
      column_names_.push_back(decl.provides[o].name);
    }
  if (kind_ == StageKind::Interaction) {
    if (native_resolver(ctx.world().plugins(), decl.info.target)) {
      native_target_ = bind_native_target(ctx);
      target_functions_ = native_target_->functions();
    } else {
      lua_target_ = &ctx.target<LuaResolver>();
      target_functions_ = lua_target_->functions();
    }
  }

  // The settings the scene gave, over the defaults the mod declared.
  ctx.settings().check_known(decl_name_, decl.settings);
  settings_ = ctx.settings();

  lua_State* L = mod_->state();
  StackGuard guard(L);
  // The stage's blocks and declarations are built outside a protected call
  // (and the prelude runs no code of the mod): from the host's reserve, so
  // that a mod at the edge of its memory cannot make a new stage fail.
  MemoryBudget::HostScope building(mod_->host().memory());
  lua_rawgeti(L, LUA_REGISTRYINDEX, mod_->prelude_ref("new_stage"));
  const int fn = lua_gettop(L);
  lua_pushlightuserdata(L, this);
  const std::size_t n = std::max<std::size_t>(1, sources_.size());
  infos_ = static_cast<abi::Column*>(lua_newuserdata(L, n * sizeof(abi::Column)));
  std::memset(static_cast<void*>(infos_), 0, n * sizeof(abi::Column));
  call_ = new (lua_newuserdata(L, sizeof(abi::Call))) abi::Call{};
  bulks_ = static_cast<abi::Bulk*>(lua_newuserdata(L, kMaxBulk * sizeof(abi::Bulk)));
  std::memset(static_cast<void*>(bulks_), 0, kMaxBulk * sizeof(abi::Bulk));

  // The declarations, as the prelude wants them.
  lua_createtable(L, 0, 10);
  const int d = lua_gettop(L);
  lua_pushstring(L, decl_name_.c_str());
  lua_setfield(L, d, "name");
  lua_pushstring(L, kind_name(kind_));
  lua_setfield(L, d, "kind");
  if (!ctx.area().empty()) {
    lua_pushstring(L, ctx.area().c_str());
    lua_setfield(L, d, "area");
  }
  lua_createtable(L, int(sources_.size()), 0);
  for (std::size_t k = 0; k < sources_.size(); ++k) {
    const Source& s = sources_[k];
    lua_createtable(L, 0, 5);
    lua_pushstring(L, column_names_[k].c_str());
    lua_setfield(L, -2, "name");
    lua_pushinteger(L, abi_kind(s.kind));
    lua_setfield(L, -2, "kind");
    lua_pushboolean(L, s.writable && s.what == Source::Property);
    lua_setfield(L, -2, "writable");
    lua_pushboolean(L, s.what == Source::Output);
    lua_setfield(L, -2, "output");
    if (s.what == Source::DerivedInput) {
      lua_pushstring(L, s.set->name().c_str());
      lua_setfield(L, -2, "set");
    }
    if (s.kind == PropertyKind::Enum) {
      push_string_list(L, props.def(s.property).enum_values);
      lua_setfield(L, -2, "values");
    }
    lua_rawseti(L, -2, int(k) + 1);
  }
  lua_setfield(L, d, "columns");
  if (kind_ == StageKind::Resolver) {
    push_functions(L, decl.functions);
    lua_setfield(L, d, "functions");
  }
  if (kind_ == StageKind::Interaction) {
    lua_createtable(L, 0, 2);
    lua_pushstring(L, decl.info.target.c_str());
    lua_setfield(L, -2, "name");
    push_functions(L, target_functions_);
    // Functions the native target takes as load records written in place.
    in_place_ = false;
    for (std::size_t i = 0; native_target_ && i < target_functions_.size(); ++i)
      in_place_ = in_place_ || native_target_->record_kind(std::int32_t(i)) >= 0;
    if (in_place_) {
      for (std::size_t i = 0; i < target_functions_.size(); ++i) {
        const int kind = native_target_->record_kind(std::int32_t(i));
        if (kind < 0) continue;
        lua_rawgeti(L, -1, int(i) + 1);
        lua_pushinteger(L, kind);
        lua_setfield(L, -2, "record");
        lua_pop(L, 1);
      }
    }
    lua_setfield(L, -2, "functions");
    lua_setfield(L, d, "target");
  }
  lua_pushboolean(L, collisions_ != nullptr);
  lua_setfield(L, d, "contacts");

  push_settings(decl);
  lua_setfield(L, d, "settings");

  mod_->push_state();
  mod_->host().call(6, 1, where_);
  record_ref_ = luaL_ref(L, LUA_REGISTRYINDEX);
  (void)fn;
  rebind(decl);
  mod_->attach(this);
}

void LuaStage::push_settings(const StageDecl& decl) {
  lua_State* L = mod_->state();
  // The mod's defaults (its table's `settings`), then the scene's.
  lua_newtable(L);
  const int settings = lua_gettop(L);
  lua_rawgeti(L, LUA_REGISTRYINDEX, decl.def_ref);
  lua_pushliteral(L, "settings");
  lua_rawget(L, -2);  // raw: outside a protected call, no code of the mod may run
  if (lua_istable(L, -1))
    for (lua_pushnil(L); lua_next(L, -2);) {
      lua_pushvalue(L, -2);
      lua_insert(L, -2);
      lua_rawset(L, settings);
    }
  lua_pop(L, 2);
  for (const auto& [key, value] : settings_.values()) {
    lua_pushstring(L, key.c_str());
    std::visit(
        [&](const auto& v) {
          using T = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<T, double>)
            lua_pushnumber(L, v);
          else if constexpr (std::is_same_v<T, std::int64_t>)
            lua_pushnumber(L, double(v));
          else if constexpr (std::is_same_v<T, bool>)
            lua_pushboolean(L, v);
          else if constexpr (std::is_same_v<T, std::string>)
            lua_pushlstring(L, v.data(), v.size());
          else if constexpr (std::is_same_v<T, Vec3>) {
            lua_createtable(L, 3, 0);
            lua_pushnumber(L, v.x), lua_rawseti(L, -2, 1);
            lua_pushnumber(L, v.y), lua_rawseti(L, -2, 2);
            lua_pushnumber(L, v.z), lua_rawseti(L, -2, 3);
          } else
            lua_pushnil(L);
        },
        value);
    lua_rawset(L, settings);
  }
}

LuaStage::~LuaStage() {
  mod_->detach(this);
  // The Lua side may keep proxies of this stage (a mod that stored them):
  // with every count at zero they refuse to touch anything.
  for (std::size_t k = 0; k < std::max<std::size_t>(1, sources_.size()); ++k)
    infos_[k] = abi::Column{};
  call_->in_call = 0;
  ++call_->epoch;
  call_->cmd = nullptr;
  call_->contacts = nullptr;
  for (int b = 0; b < kMaxBulk; ++b) bulks_[b] = abi::Bulk{};
  luaL_unref(mod_->state(), LUA_REGISTRYINDEX, record_ref_);
}

void LuaStage::reset_state() {
  lua_State* L = mod_->state();
  StackGuard guard(L);
  lua_rawgeti(L, LUA_REGISTRYINDEX, mod_->prelude_ref("set_state"));
  lua_rawgeti(L, LUA_REGISTRYINDEX, record_ref_);
  mod_->push_state();
  mod_->host().call(2, 0, where_);
}

void LuaStage::rebind(const StageDecl& decl) {
  lua_State* L = mod_->state();
  StackGuard guard(L);
  lua_rawgeti(L, LUA_REGISTRYINDEX, mod_->prelude_ref("bind"));
  lua_rawgeti(L, LUA_REGISTRYINDEX, record_ref_);
  lua_rawgeti(L, LUA_REGISTRYINDEX, decl.def_ref);
  push_settings(decl);  // a reload may have changed the defaults
  mod_->host().call(3, 0, where_);
  where_ = decl.where;
  disabled_ = false;
  reported = false;
  reason_.clear();
}

bool LuaStage::invoke(const WorldView& view, ResolverAccess* access, const char* phase, double dt) {
  // Whatever way the call ends (returns, fails, or a C++ exception leaves
  // it), everything lent to Lua for it is taken back (end_call).
  struct Ending {
    LuaStage& stage;
    ~Ending() { stage.end_call(); }
  };
  InputError failure("");
  bool ok = false;
  {
    Ending ending{*this};
    ok = run_call(view, access, phase, dt, failure);
  }
  if (ok) return true;
  // Published as events now; reported (and logged) by ModRuntime::poll.
  if (mod_->stopped()) {
    if (!mod_->stop_event_sent) {
      mod_->stop_event_sent = true;
      view.emit(Event{.type = "mod_stopped", .text = mod_->stop_reason()});
    }
    return false;
  }
  disabled_ = true;
  reason_ = "stage '" + instance_ + "' of mod '" + mod_->name() +
            "' failed and is disabled until the mod is reloaded: " + failure.what();
  view.emit(Event{.type = "stage_disabled", .text = reason_});
  return false;
}

bool LuaStage::run_call(const WorldView& view, ResolverAccess* access, const char* phase, double dt,
                        InputError& failure) {
  view_ = &view;
  contacts_made_ = 0;
  access_ = access;
  if (access) writers_.assign(sources_.size(), AnyWriter{});
  call_->dt = dt;
  call_->time = view.time();
  call_->step = double(view.step());
  call_->slots = std::uint32_t(view.store().slot_count());
  if (kind_ == StageKind::Interaction) {
    if (commands_.size() < kCommandBuffer) commands_.resize(kCommandBuffer);
    refresh_ids(view.store());
    call_->ids = ids_.data();
    call_->buf = commands_.data();
    call_->buf_len = 0;
    call_->buf_cap = double(commands_.size());
    if (in_place_) {
      call_->loads = native_target_->open_records(records_room_);
      call_->buf_cap = double(records_room_);
    }
  }
  // On only now that everything it lends is in place.
  call_->in_call = 1;
  ++call_->epoch;
  bool ok = mod_->run_stage(record_ref_, phase, dt, view.time(), view.step(), where_, &failure);
  if (ok && kind_ == StageKind::Interaction) ok = count_commands(failure);
  // The commands are performed when the call succeeded, all of them; a
  // failed call queues nothing.
  if (ok && kind_ == StageKind::Interaction && !(perform_commands() && perform_bulk())) {
    ok = false;
    failure = InputError(ErrorLocation{where_.file, 0, ""}, last_error_);
  }
  return ok;
}

void LuaStage::end_call() noexcept {
  // The call's lists and buffers are cleared in the blocks the prelude reads,
  // so that every handle a mod kept (a column, a bulk buffer, an iterator, a
  // lone function of w) refuses from now on, and the epoch moves, so that
  // nothing of this call passes for the next one.
  for (int b = 0; b < bulk_used_; ++b) bulks_[b] = abi::Bulk{};
  bulk_used_ = 0;
  call_->buf = nullptr;
  call_->buf_len = call_->buf_cap = 0;
  if (call_->loads) {  // a failed call queues nothing
    try {
      native_target_->close_records(0, view_->store(), true);
    } catch (...) {  // closing keeps nothing: it cannot fail, but must not throw here
    }
    call_->loads = nullptr;
  }
  call_->ids = nullptr;
  for (std::size_t k = 0; k < sources_.size(); ++k) infos_[k] = abi::Column{};
  call_->in_call = 0;
  ++call_->epoch;
  call_->cmd = nullptr;
  call_->cmd_count = 0;
  call_->contacts = nullptr;
  call_->contact_count = 0;
  contacts_made_ = 0;
  if (access_) writers_.clear();
  view_ = nullptr;
  access_ = nullptr;
}

std::int32_t LuaStage::refuse(const char* what, const char* prefix) noexcept {
  try {
    last_error_ = std::string(prefix) + (what ? what : "an unknown error in the host");
  } catch (...) {
    last_error_.clear();  // host_last_error says so
  }
  return 1;
}

LuaStage* LuaStage::stage_in_call(lua_State* L) {
  LuaStage* st = stage_of(L);
  // The prelude checks the call first; this guards the host's own pointers.
  if (!st->view_) luaL_error(L, "stage '%s' is not in a call", st->instance_.c_str());
  return st;
}

bool LuaStage::check_slot(double slot, std::uint32_t& out) {
  const double slots = double(view_->store().slot_count());
  if (!(slot >= 0 && slot < slots) || std::floor(slot) != slot) {
    error("no object in slot " + number_text(slot));
    return false;
  }
  out = std::uint32_t(slot);
  if (!view_->store().id_at(out)) {
    error("the object in slot " + number_text(slot) + " was destroyed");
    return false;
  }
  return true;
}

void LuaStage::fetch(std::size_t k) {
  const Source& s = sources_[k];
  abi::Column& info = infos_[k];
  info = abi::Column{};
  const auto slots = std::uint32_t(view_->store().slot_count());
  std::span<const std::uint32_t> members;
  if (s.what == Source::Property) {
    auto take = [&]<class T>(std::type_identity<T>) {
      const ColumnView<T> v = view_->column<T>(s.property);
      members = v.members();
      info.any = view_->store().typed<T>(s.property).values().data();
      if constexpr (std::is_constructible_v<AnyWriter, ColumnWriter<T>>)
        if (s.writable && access_) writers_[k] = access_->writer<T>(s.property);
    };
    switch (s.kind) {
      case PropertyKind::Number:
        take(std::type_identity<double>{});
        break;
      case PropertyKind::Integer:
        take(std::type_identity<std::int64_t>{});
        break;
      case PropertyKind::Bool:
        take(std::type_identity<std::uint8_t>{});
        break;
      case PropertyKind::Vec3:
        take(std::type_identity<Vec3>{});
        break;
      case PropertyKind::Quat:
        take(std::type_identity<Quat>{});
        break;
      case PropertyKind::Enum:
        take(std::type_identity<EnumValue>{});
        break;
      case PropertyKind::Ref:
        take(std::type_identity<ObjectId>{});
        break;
      case PropertyKind::String:
        take(std::type_identity<std::string>{});
        info.any = nullptr;
        break;
      case PropertyKind::RefList:
        members = view_->column<RefList>(s.property).members();
        break;
    }
    info.members = members.data();
    info.count = std::uint32_t(members.size());
    info.n = slots;
  } else if (s.what == Source::Output) {
    fill_outputs(k, info);
  } else {
    s.set->describe(s.output, info);
  }
}

void LuaStage::refresh_ids(const PropertyStore& store) {
  const std::size_t slots = store.slot_count();
  if (ids_version_ == store.structure_version() && ids_.size() == slots) return;
  ids_.resize(std::max<std::size_t>(1, slots));  // never empty: data() is non-null
  for (std::size_t s = 0; s < slots; ++s) {
    const ObjectId id = store.id_at(std::uint32_t(s));
    ids_[s] = id ? std::uint64_t(id.generation) << 32 | id.index : 0;
  }
  ids_.resize(slots);
  ids_version_ = store.structure_version();
}

bool LuaStage::perform_commands() {
  const double* b = commands_.data();
  const auto n = std::size_t(call_->buf_len);
  const PropertyStore& store = view_->store();
  // The prelude checked every slot against ids_ as it queued; those ids
  // still hold if no object came or went since (nothing can in a stage's
  // call, but the check is one comparison).
  const bool checked = ids_version_ == store.structure_version();
  if (call_->loads) {
    // The records are in the target's queue already: keep those written.
    call_->loads = nullptr;
    records_room_ = std::max<std::size_t>(16, n);  // the last call's need: room enough, no more
    if (std::string problem = native_target_->close_records(n, store, checked); !problem.empty())
      return error(problem), false;
    return true;
  }
  if (native_target_) {
    if (std::string problem = native_target_->perform(b, n, store, checked); !problem.empty())
      return error(problem), false;
    return true;
  }
  for (std::size_t o = 0; o < n;) {
    const auto fn = std::size_t(b[o]);
    if (fn >= target_functions_.size())
      return error("a command of an unknown interaction function"), false;
    const FunctionDecl& f = target_functions_[fn];
    const std::size_t stride = 2 + std::size_t(widths(f.args));
    if (o + stride > n) return error("a truncated command"), false;
    // The prelude checked kinds, ranges and finiteness where the mod's line
    // was known; what remains is whether the objects still exist.
    // A slot read from the buffer is converted only once it is known to be
    // one: a double outside uint32's range is undefined behaviour to convert
    // (UBSan, found by the fuzzers with an object argument of -1).
    auto live = [&](double slot) {
      return slot >= 0 && slot < double(store.slot_count()) ? store.id_at(std::uint32_t(slot))
                                                            : ObjectId{};
    };
    const ObjectId id = live(b[o + 1]);
    if (!id)
      return error("'" + f.name + "' on the object in slot " + number_text(b[o + 1]) +
                   ", which was destroyed"),
             false;
    std::size_t a = o + 2;
    for (ArgKind k : f.args) {
      if (k == ArgKind::Object && !live(b[a]))
        return error("'" + f.name + "' of " + store.describe(id) + ": no object in slot " +
                     number_text(b[a])),
               false;
      a += std::size_t(width(k));
    }
    if (native_target_) {
      native_target_->call(std::int32_t(fn), id, b + o + 2);
    } else if (std::string problem = lua_target_->push(std::int32_t(fn), id.index, b + o + 2,
                                                       std::int32_t(stride - 2));
               !problem.empty()) {
      return error(problem), false;
    }
    o += stride;
  }
  return true;
}

bool LuaStage::perform_bulk() {
  for (int b = 0; b < bulk_used_; ++b) {
    const abi::Bulk& bulk = bulks_[b];
    const abi::Column& col = infos_[bulk.column];
    // The column's members as fetched for this call: live objects in the
    // stage's area; the prelude refused writes to any other slot, and
    // values that are not finite.
    const std::span<const std::uint32_t> members(col.members, col.count);
    if (in_place_ && native_target_->record_kind(bulk.function) >= 0)
      continue;  // written in place as load records, kept with the others
    if (native_target_) {
      native_target_->perform_each(bulk.function, members, bulk.present, bulk.values, bulk.width,
                                   view_->store());
      continue;
    }
    for (std::uint32_t s : members)
      if (bulk.present[s] == 1)
        if (std::string problem = lua_target_->push(
                bulk.function, s, bulk.values + std::size_t(bulk.width) * s, bulk.width);
            !problem.empty())
          return error(problem), false;
  }
  return true;
}

// --- the FFI entry points -------------------------------------------------------------

std::int32_t LuaStage::api_fetch(void* p, std::int32_t column) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->view_) return st->error("not in a call");
    if (column < 0 || std::size_t(column) >= st->sources_.size())
      return st->error("no such column");
    st->fetch(std::size_t(column));
    return 0;
  } catch (const std::exception& e) {
    return st->refuse(e.what());
  } catch (...) {
    return st->refuse(nullptr);
  }
}

std::int32_t LuaStage::api_set_scalar(void* p, std::int32_t k, double slot, double v) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->access_ || k < 0 || std::size_t(k) >= st->sources_.size() ||
        !st->sources_[std::size_t(k)].writable)
      return st->error("this column is not writable here");
    std::uint32_t s;
    if (!st->check_slot(slot, s)) return 1;
    const Source& src = st->sources_[std::size_t(k)];
    const PropertyDef& def = st->world_.properties().def(src.property);
    auto& w = st->writers_[std::size_t(k)];
    auto refuse = [&](const std::string& why) {
      return st->error("'" + def.name + "' of " +
                       st->view_->store().describe(st->view_->store().id_at(s)) + " " + why);
    };
    switch (src.kind) {
      case PropertyKind::Number:
        if (auto why = bounds_problem(def, v); !why.empty()) return refuse(why);
        std::get<ColumnWriter<double>>(w).set(s, v);
        return 0;
      case PropertyKind::Integer:
        if (std::floor(v) != v) return refuse("must be a whole number, got " + number_text(v));
        if (auto why = bounds_problem(def, v); !why.empty()) return refuse(why);
        std::get<ColumnWriter<std::int64_t>>(w).set(s, std::int64_t(v));
        return 0;
      case PropertyKind::Bool:
        std::get<ColumnWriter<std::uint8_t>>(w).set(s, v != 0 ? 1 : 0);
        return 0;
      case PropertyKind::Enum:
        if (!(v >= 0 && v < double(def.enum_values.size()))) return refuse("has no such value");
        std::get<ColumnWriter<EnumValue>>(w).set(s, EnumValue{std::int32_t(v)});
        return 0;
      default:
        return refuse("is not a number");
    }
  } catch (const std::exception& e) {
    return st->refuse(e.what());
  } catch (...) {
    return st->refuse(nullptr);
  }
}

std::int32_t LuaStage::api_set_vec3(void* p, std::int32_t k, double slot, double x, double y,
                                    double z) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->access_ || k < 0 || std::size_t(k) >= st->sources_.size() ||
        !st->sources_[std::size_t(k)].writable ||
        st->sources_[std::size_t(k)].kind != PropertyKind::Vec3)
      return st->error("this column is not a writable vec3 here");
    std::uint32_t s;
    if (!st->check_slot(slot, s)) return 1;
    const PropertyDef& def = st->world_.properties().def(st->sources_[std::size_t(k)].property);
    for (double c : {x, y, z})
      if (auto why = bounds_problem(def, c); !why.empty())
        return st->error("'" + def.name + "' of " +
                         st->view_->store().describe(st->view_->store().id_at(s)) + " " + why);
    if (def.nonzero && x == 0 && y == 0 && z == 0)
      return st->error("'" + def.name + "' must not be the zero vector");
    std::get<ColumnWriter<Vec3>>(st->writers_[std::size_t(k)]).set(s, Vec3{x, y, z});
    return 0;
  } catch (const std::exception& e) {
    return st->refuse(e.what());
  } catch (...) {
    return st->refuse(nullptr);
  }
}

std::int32_t LuaStage::api_set_quat(void* p, std::int32_t k, double slot, double w, double x,
                                    double y, double z) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->access_ || k < 0 || std::size_t(k) >= st->sources_.size() ||
        !st->sources_[std::size_t(k)].writable ||
        st->sources_[std::size_t(k)].kind != PropertyKind::Quat)
      return st->error("this column is not a writable quat here");
    std::uint32_t s;
    if (!st->check_slot(slot, s)) return 1;
    const double norm = std::sqrt(w * w + x * x + y * y + z * z);
    if (!std::isfinite(norm) || norm == 0)
      return st->error("a rotation must be a finite, non-zero quaternion");
    std::get<ColumnWriter<Quat>>(st->writers_[std::size_t(k)])
        .set(s, Quat{w / norm, x / norm, y / norm, z / norm});
    return 0;
  } catch (const std::exception& e) {
    return st->refuse(e.what());
  } catch (...) {
    return st->refuse(nullptr);
  }
}

std::int32_t LuaStage::api_has(void* p, std::int32_t k, double slot) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->view_ || k < 0 || std::size_t(k) >= st->sources_.size()) {
      st->error("not in a call");
      return -1;
    }
    if (!(slot >= 0 && slot < double(st->view_->store().slot_count())) || std::floor(slot) != slot)
      return 0;
    const auto s = std::uint32_t(slot);
    const Source& src = st->sources_[std::size_t(k)];
    if (src.what == Source::Property) {
      const ColumnBase& c = st->view_->store().column(src.property);
      if (!c.has(s)) return 0;
      return (!st->view_->scope() || st->view_->scope()->contains(s)) ? 1 : 0;
    }
    const abi::Column& info = st->infos_[k];
    return info.n > s && info.out_present && info.out_present[s] ? 1 : 0;
  } catch (const std::exception& e) {
    return -st->refuse(e.what());
  } catch (...) {
    return -st->refuse(nullptr);
  }
}

bool LuaStage::count_commands(InputError& failure) {
  // The mod's budget of queued commands (mod_state.hpp), counted before they
  // are performed: over it, the call's commands are refused.
  const auto len = std::size_t(call_->buf_len);
  std::uint64_t n = len;
  std::size_t bytes = len * sizeof(abi::LoadRecord);
  if (!call_->loads) {
    n = 0;
    bytes = len * sizeof(double);
    for (std::size_t o = 0; o < len && std::size_t(commands_[o]) < target_functions_.size(); ++n)
      o += 2 + std::size_t(widths(target_functions_[std::size_t(commands_[o])].args));
  }
  std::string why = mod_->count_commands(n, bytes);
  if (why.empty()) return true;
  mod_->place_stop(where_);
  failure = InputError(why);
  return false;
}

std::int32_t LuaStage::api_grow(void* p) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->view_ || st->kind_ != StageKind::Interaction)
      return st->error("only an interaction may queue commands, while it runs");
    // The host memory the queue would take counts against the mod's budget.
    const std::size_t room = std::size_t(st->call_->buf_cap) * 2;
    const bool records = st->call_->loads != nullptr;  // one command each; else 2 to 14 doubles
    const std::size_t unit = records ? sizeof(abi::LoadRecord) : sizeof(double);
    if (std::string why = st->mod_->may_queue(room * unit, records ? room / 2 : room / 28);
        !why.empty())
      return st->error(why);
    if (st->call_->loads) {
      st->call_->loads = st->native_target_->open_records(room);
      st->call_->buf_cap = double(room);
      return 0;
    }
    st->commands_.resize(st->commands_.size() * 2);
    st->call_->buf = st->commands_.data();
    st->call_->buf_cap = double(st->commands_.size());
    return 0;
  } catch (const std::exception& e) {
    return st->refuse(e.what(), "cannot queue more commands: ");
  } catch (...) {
    return st->refuse(nullptr, "cannot queue more commands: ");
  }
}

std::int32_t LuaStage::api_commands(void* p, std::int32_t fn) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->access_) return st->error("commands are read in the resolver's advance");
    return st->commands(fn);
  } catch (const std::exception& e) {
    return st->refuse(e.what());
  } catch (...) {
    return st->refuse(nullptr);
  }
}

std::int32_t LuaStage::api_contacts(void* p, std::int32_t which) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->view_ || !st->collisions_)
      return st->error(
          "declare a contact set in `derived` (the native set of contacts) to read contacts");
    if (which < 0 || which >= kContactLists) return st->error("no such list of contacts");
    // Each list is made once per call and then left alone: an iterator over
    // one stays valid while the stage asks for another, or the same again.
    std::vector<abi::Contact>& list = st->contacts_[which];
    const std::uint32_t made = 1u << which;
    if (st->contacts_made_ & made) {
      st->call_->contacts = list.data();
      st->call_->contact_count = std::uint32_t(list.size());
      return 0;
    }
    list.clear();
    const ContactSet& c = *st->collisions_;
    auto add = [&](std::span<const ContactPair> pairs, bool began) {
      for (const auto& pair : pairs) {
        abi::Contact out{};
        out.a = pair.a.index;
        out.b = pair.b.index;
        out.points = std::int32_t(pair.count);
        out.began = began ? 1 : 0;
        out.speed = pair.normal_speed;
        out.depth = pair.depth;
        out.impulse = pair.normal_impulse;
        out.total_impulse = pair.total_impulse;
        if (pair.count > 0) {
          const auto pts = c.points(pair);
          out.normal = pts[0].normal;
          out.point = pts[0].position;
        }
        list.push_back(out);
      }
    };
    if (which == 0 || which == 3) add(c.began(), true);
    if (which == 1 || which == 3) add(c.ongoing(), false);
    if (which == 2) add(c.ended(), false);
    if (which == 3)  // touching: in (a, b) order, as the set keeps them
      std::sort(list.begin(), list.end(), [](const abi::Contact& x, const abi::Contact& y) {
        return x.a < y.a || (x.a == y.a && x.b < y.b);
      });
    st->contacts_made_ |= made;
    st->call_->contacts = list.data();
    st->call_->contact_count = std::uint32_t(list.size());
    return 0;
  } catch (const std::exception& e) {
    return st->refuse(e.what());
  } catch (...) {
    return st->refuse(nullptr);
  }
}

std::int32_t LuaStage::api_bulk(void* p, std::int32_t fn, std::int32_t column) noexcept {
  auto* st = static_cast<LuaStage*>(p);
  try {
    if (!st->view_ || st->kind_ != StageKind::Interaction) {
      st->error("only an interaction may queue commands, while it runs");
      return -1;
    }
    if (fn < 0 || std::size_t(fn) >= st->target_functions_.size()) {
      st->error("no such interaction function");
      return -1;
    }
    const FunctionDecl& f = st->target_functions_[std::size_t(fn)];
    if (f.args.size() != 1 || f.args[0] == ArgKind::Object) {
      st->error("'" + f.name + "' has no bulk form (only functions of one number or vec3 have)");
      return -1;
    }
    if (column < 0 || std::size_t(column) >= st->sources_.size() ||
        st->sources_[std::size_t(column)].what == Source::Output) {
      st->error("the bulk form of '" + f.name + "' takes a column the stage reads");
      return -1;
    }
    for (int b = 0; b < st->bulk_used_; ++b)  // the same buffer again in the same call
      if (st->bulks_[b].function == fn && st->bulks_[b].column == column) return b;
    if (st->bulk_used_ == kMaxBulk) {
      st->error("more than " + std::to_string(kMaxBulk) + " bulk buffers in one call");
      return -1;
    }
    abi::Column& info = st->infos_[column];
    if (info.n == 0) st->fetch(std::size_t(column));
    const int b = st->bulk_used_;
    BulkStore& store = st->bulk_store_[b];
    const int width = ::alloy::width(f.args[0]);
    // 2 everywhere, then 0 on the members: a write is refused outside them.
    // Storage is kept between calls (no allocation once it has grown).
    // Members are ascending and distinct: n of them ending at n-1 are every
    // slot (the common case), 0 everywhere without walking the list.
    const std::uint32_t* members = info.members;
    if (info.count == info.n && info.n > 0 && members[info.n - 1] == info.n - 1) {
      store.present.assign(info.n, 0);
    } else {
      store.present.assign(info.n, 2);
      // Locals: through the fields, each byte stored would reload them (it may alias).
      std::uint8_t* present = store.present.data();
      for (std::uint32_t j = 0, count = info.count; j < count; ++j) present[members[j]] = 0;
    }
    if (store.values.size() < std::size_t(width) * info.n)
      store.values.resize(std::size_t(width) * info.n);
    st->bulks_[b] = abi::Bulk{store.values.data(), store.present.data(), info.n, width, fn, column};
    ++st->bulk_used_;
    return b;
  } catch (const std::exception& e) {
    return -st->refuse(e.what());
  } catch (...) {
    return -st->refuse(nullptr);
  }
}

// --- host functions (rare paths, plain Lua C API) ----------------------------------------

int LuaStage::host_last_error(lua_State* L) {
  LuaStage* st = stage_of(L);
  if (st->last_error_.empty())  // refuse() could not copy the message (out of memory)
    lua_pushliteral(L, "the host refused (no message: out of memory?)");
  else
    lua_pushlstring(L, st->last_error_.data(), st->last_error_.size());
  return 1;
}

int LuaStage::host_name(lua_State* L) {
  LuaStage* st = stage_in_call(L);
  return catch_exceptions(L, [&] {
    std::uint32_t s;
    if (!st->check_slot(luaL_checknumber(L, 2), s)) throw InputError(st->last_error_);
    const std::string n = st->view_->store().describe(st->view_->store().id_at(s));
    lua_pushlstring(L, n.data(), n.size());
    return 1;
  });
}

int LuaStage::host_find(lua_State* L) {
  LuaStage* st = stage_in_call(L);
  const char* name = luaL_checkstring(L, 2);  // converts a number; runs no metamethod
  return catch_exceptions(L, [&] {
    const ObjectId id = st->view_->store().find(name);
    if (!id) return 0;
    lua_pushnumber(L, id.index);
    return 1;
  });
}

int LuaStage::host_alive(lua_State* L) {
  LuaStage* st = stage_in_call(L);
  const double slot = luaL_checknumber(L, 2);
  lua_pushboolean(L, slot >= 0 && slot < double(st->view_->store().slot_count()) &&
                         std::floor(slot) == slot &&
                         bool(st->view_->store().id_at(std::uint32_t(slot))));
  return 1;
}

int LuaStage::host_emit(lua_State* L) {
  LuaStage* st = stage_in_call(L);
  return catch_exceptions(L, [&] {
    Event e;
    e.type = luaL_checkstring(L, 2);
    if (e.type.empty()) throw InputError("w:emit needs an event type");
    if (!lua_isnoneornil(L, 3)) {
      luaL_checktype(L, 3, LUA_TTABLE);
      std::vector<std::pair<std::string, double>> values;
      for (lua_pushnil(L); lua_next(L, 3); lua_pop(L, 1)) {
        if (lua_type(L, -2) != LUA_TSTRING) throw InputError("w:emit: fields are named");
        const std::string key = lua_tostring(L, -2);
        if (key == "a" || key == "b") {
          std::uint32_t s;
          if (!st->check_slot(luaL_checknumber(L, -1), s))
            throw InputError("w:emit '" + key + "': " + st->last_error_);
          (key == "a" ? e.a : e.b) = st->view_->store().id_at(s);
        } else if (key == "text") {
          if (lua_type(L, -1) != LUA_TSTRING) throw InputError("w:emit: 'text' must be a string");
          e.text = lua_tostring(L, -1);
        } else if (lua_type(L, -1) == LUA_TNUMBER) {
          values.emplace_back(key, lua_tonumber(L, -1));
        } else {
          throw InputError("w:emit: field '" + key + "' must be a number (or a, b, text)");
        }
      }
      std::sort(values.begin(), values.end());  // a fixed order, whatever the table's
      e.values = std::move(values);
    }
    // The mod's budget of events (mod_state.hpp): over it, the event is refused.
    std::size_t bytes = e.type.size() + e.text.size();
    for (const auto& [k, v] : e.values) bytes += k.size() + sizeof v;
    if (std::string why = st->mod_->count_event(bytes); !why.empty()) throw InputError(why);
    st->view_->emit(std::move(e));
    return 0;
  });
}

// --- energy: w:energy(kind, account, joules) (docs/modding.md "Energy") -----------------

std::string LuaStage::transfer_refused(const std::string& account) const {
  // The rigid body books the loads an interaction queues as a transfer named
  // after its physics: its name less "<target>_from_" and the area
  // (work_account in rigid_body_energy.cpp). That name, and the mod's own
  // "<mod>." names, are the only transfers a mod's stage may be a side of:
  // it cannot join a coupling of native stages and cancel their mismatch.
  auto physics = [](const std::string& name, const std::string& target) {
    const std::string prefix = target + "_from_";
    return !target.empty() && name.starts_with(prefix) ? name.substr(prefix.size()) : name;
  };
  const std::string own = physics(decl_name_, target_);
  const std::string mine = mod_->name() + ".";
  if (account != own && !(account.size() > mine.size() && account.starts_with(mine)))
    return "w:energy: transfer '" + account + "' is not this stage's: a mod's stage reports a " +
           "transfer only under its physics' name ('" + own + "', the name its target books " +
           "its loads by) or under '" + mine + "<name>'";
  // A name native stages book under is theirs, even where a mod's stage's
  // name happens to make it (an interaction called <target>_from_light).
  const PluginRegistry& registry = world_.plugins();
  for (const std::string& n : registry.order()) {
    const PluginDef* d = registry.find(n);
    if (d && d->info.owner.empty() &&
        (n == account || physics(n, d->info.target) == account || d->info.provides == account))
      return "w:energy: transfer '" + account + "' belongs to the native plugin '" + n + "'";
  }
  return "";
}

int LuaStage::host_energy(lua_State* L) {
  LuaStage* st = stage_in_call(L);
  // Every argument converted before any C++ object is made (a Lua error
  // here unwinds; none of these runs code of the mod).
  const char* kind_text = luaL_checkstring(L, 2);
  std::size_t n = 0;
  const char* name = luaL_checklstring(L, 3, &n);
  const double joules = luaL_checknumber(L, 4);
  return catch_exceptions(L, [&] {
    static constexpr std::pair<std::string_view, EnergyKind> kKinds[] = {
        {"source", EnergyKind::Source},
        {"sink", EnergyKind::Sink},
        {"store", EnergyKind::Store},
        {"transfer", EnergyKind::Transfer}};
    const auto kind = std::find_if(std::begin(kKinds), std::end(kKinds),
                                   [&](const auto& k) { return k.first == kind_text; });
    if (kind == std::end(kKinds))
      throw InputError(std::string("w:energy: the kind must be 'source', 'sink', 'store' or ") +
                       "'transfer', not '" + std::string(kind_text).substr(0, 40) + "'");
    const std::string account(name, std::min<std::size_t>(n, 200));
    if (n == 0 || n > 64)
      throw InputError("w:energy: an account's name has 1 to 64 bytes ('" + account + "')");
    const ModBudget& budget = st->mod_->budget();
    if (!std::isfinite(joules))
      throw InputError("w:energy '" + account + "': the energy must be finite, got " +
                       number_text(joules) + " J");
    if (std::abs(joules) > budget.energy_joules)
      throw InputError("w:energy '" + account + "': " + number_text(joules) +
                       " J is beyond what one report may carry (" +
                       number_text(budget.energy_joules) + " J, its budget energy_joules)");
    if (std::string why = st->mod_->count_energy_report(); !why.empty()) throw InputError(why);
    auto it = std::find_if(st->booked_.begin(), st->booked_.end(), [&](const Booked& b) {
      return b.kind == kind->second && b.account == account;
    });
    if (it == st->booked_.end()) {
      if (st->booked_.size() >= budget.energy_accounts_per_stage)
        throw InputError("w:energy '" + account + "': stage '" + st->decl_name_ +
                         "' already keeps " + std::to_string(st->booked_.size()) +
                         " accounts (its budget energy_accounts_per_stage)");
      if (kind->second == EnergyKind::Transfer)
        if (std::string why = st->transfer_refused(account); !why.empty()) throw InputError(why);
      st->booked_.push_back({account, kind->second, 0.0});
      it = st->booked_.end() - 1;
    }
    // A store is a level (the last report wins); a flow adds up.
    it->joules = kind->second == EnergyKind::Store ? joules : it->joules + joules;
    return 0;
  });
}

void LuaStage::report_books(EnergyReport& out) {
  for (Booked& b : booked_) switch (b.kind) {
      case EnergyKind::Source:
        out.source(b.account, std::exchange(b.joules, 0.0));
        break;
      case EnergyKind::Sink:
        out.sink(b.account, std::exchange(b.joules, 0.0));
        break;
      case EnergyKind::Transfer:
        out.transfer(b.account, std::exchange(b.joules, 0.0));
        break;
      case EnergyKind::Store:
        out.store(b.account, b.joules);
        break;
    }
}

int LuaStage::host_slow_get(lua_State* L) {
  LuaStage* st = stage_in_call(L);
  return catch_exceptions(L, [&] {
    const auto k = std::size_t(luaL_checkinteger(L, 2));
    std::uint32_t s;
    if (k >= st->sources_.size() || !st->view_) throw InputError("not in a call");
    if (!st->check_slot(luaL_checknumber(L, 3), s)) throw InputError(st->last_error_);
    const Source& src = st->sources_[k];
    const ColumnBase& c = st->view_->store().column(src.property);
    if (!c.has(s)) return 0;
    if (src.kind == PropertyKind::String) {
      const std::string& v = st->view_->store().typed<std::string>(src.property)[s];
      lua_pushlstring(L, v.data(), v.size());
      return 1;
    }
    if (src.kind == PropertyKind::RefList) {
      const RefList& v = st->view_->store().typed<RefList>(src.property)[s];
      lua_createtable(L, int(v.size()), 0);
      int i = 0;
      for (ObjectId id : v)
        if (st->view_->store().alive(id)) lua_pushnumber(L, id.index), lua_rawseti(L, -2, ++i);
      return 1;
    }
    return 0;
  });
}

int LuaStage::host_slow_set(lua_State* L) {
  LuaStage* st = stage_in_call(L);
  // Every argument converted before any C++ object or reference is made (a
  // Lua error here unwinds; none of these runs code of the mod).
  const auto k = std::size_t(luaL_checkinteger(L, 2));
  const double slot = luaL_checknumber(L, 3);
  std::size_t n = 0;
  const char* text = luaL_checklstring(L, 4, &n);
  return catch_exceptions(L, [&] {
    std::uint32_t s;
    if (k >= st->sources_.size() || !st->access_ || !st->sources_[k].writable)
      throw InputError("not writable here");
    if (!st->check_slot(slot, s)) throw InputError(st->last_error_);
    if (st->sources_[k].kind != PropertyKind::String)
      throw InputError("writing '" + st->column_names_[k] +
                       "' from Lua is not supported (numbers, vectors, "
                       "rotations, booleans, enums and strings are)");
    std::get<ColumnWriter<std::string>>(st->writers_[k]).set(s, std::string(text, n));
    return 0;
  });
}

// --- the three kinds ----------------------------------------------------------------

LuaResolver::LuaResolver(std::shared_ptr<ModState> mod, const StageDecl& decl, PluginContext& ctx)
    : LuaStage(std::move(mod), decl, ctx),
      functions_(decl.functions),
      queue_(decl.functions.size()) {}

void LuaResolver::build(ResolverAccess& access) {
  if (runnable()) invoke(access, &access, "build", access.dt());
}

void LuaResolver::advance(ResolverAccess& access, double dt) {
  if (runnable()) invoke(access, &access, "advance", dt);
  for (auto& q : queue_) q.clear();  // performed, or dropped with a disabled stage
}

std::string LuaResolver::push(std::int32_t fn, std::uint32_t slot, const double* args,
                              std::int32_t nargs) {
  if (fn < 0 || std::size_t(fn) >= functions_.size()) return "no such interaction function";
  auto& q = queue_[std::size_t(fn)];
  q.push_back(double(slot));
  q.insert(q.end(), args, args + nargs);
  return "";
}

std::size_t LuaResolver::queued() const {
  std::size_t n = 0;
  for (std::size_t f = 0; f < queue_.size(); ++f)
    n += queue_[f].size() / std::size_t(1 + widths(functions_[f].args));
  return n;
}

std::int32_t LuaResolver::commands(std::int32_t fn) {
  if (fn < 0 || std::size_t(fn) >= functions_.size()) return error("no such interaction function");
  const auto& q = queue_[std::size_t(fn)];
  const auto stride = std::uint32_t(1 + widths(functions_[std::size_t(fn)].args));
  call_->cmd = q.data();
  call_->cmd_stride = stride;
  call_->cmd_count = std::uint32_t(q.size() / stride);
  return 0;
}

LuaDerivedSet::LuaDerivedSet(std::shared_ptr<ModState> mod, const StageDecl& decl,
                             PluginContext& ctx)
    : LuaStage(std::move(mod), decl, ctx), outputs_(decl.provides), data_(decl.provides.size()) {}

void LuaDerivedSet::update(const WorldView& world) {
  // Outputs are recomputed from nothing at each update: a pure function of the inputs.
  const std::size_t slots = world.store().slot_count();
  for (std::size_t o = 0; o < data_.size(); ++o) {
    Output& out = data_[o];
    out.present.assign(slots, 0);
    if (outputs_[o].kind == PropertyKind::Vec3)
      out.vec3.assign(slots, Vec3{});
    else
      out.num.assign(slots, 0.0);
  }
  const bool ok = runnable() && invoke(world, nullptr, "update", world.dt());
  for (Output& out : data_) {
    out.members.clear();
    if (!ok) std::fill(out.present.begin(), out.present.end(), 0);  // no half-made data
    for (std::uint32_t s = 0; s < out.present.size(); ++s)
      if (out.present[s]) out.members.push_back(s);
  }
}

void LuaDerivedSet::fill_outputs(std::size_t k, abi::Column& info) {
  const Output& out = data_[std::size_t(sources_[k].output)];
  Output& w = data_[std::size_t(sources_[k].output)];
  info.any = sources_[k].kind == PropertyKind::Vec3 ? static_cast<const void*>(out.vec3.data())
                                                    : static_cast<const void*>(out.num.data());
  info.out_num = w.num.data();
  info.out_vec3 = w.vec3.data();
  info.out_present = w.present.data();
  info.n = std::uint32_t(out.present.size());
  // While the set writes, its members are those written so far: they are
  // listed after the update, for its readers.
  info.members = nullptr;
  info.count = 0;
}

void LuaDerivedSet::describe(int k, abi::Column& info) const {
  const Output& out = data_[std::size_t(k)];
  info.any = outputs_[std::size_t(k)].kind == PropertyKind::Vec3
                 ? static_cast<const void*>(out.vec3.data())
                 : static_cast<const void*>(out.num.data());
  info.members = out.members.data();
  info.count = std::uint32_t(out.members.size());
  info.out_present = const_cast<std::uint8_t*>(
      out.present.data());  // has() reads it; the prelude never writes a reader's
  info.n = std::uint32_t(out.present.size());
}

LuaInteraction::LuaInteraction(std::shared_ptr<ModState> mod, const StageDecl& decl,
                               PluginContext& ctx)
    : LuaStage(std::move(mod), decl, ctx) {}

void LuaInteraction::apply(const WorldView& world) {
  if (runnable()) invoke(world, nullptr, "apply", world.dt());
}

// --- plugins ------------------------------------------------------------------------

std::unique_ptr<Stage> LuaStageFactory::operator()(PluginContext& ctx) const {
  const Program* p = mod->program();
  const StageDecl* d = p ? p->stage(stage) : nullptr;
  if (!d) throw AccessError("mod '" + mod->name() + "' does not define '" + stage + "' any more");
  switch (d->info.kind) {
    case StageKind::Resolver:
      return std::make_unique<LuaResolver>(mod, *d, ctx);
    case StageKind::Derived:
      return std::make_unique<LuaDerivedSet>(mod, *d, ctx);
    case StageKind::Interaction:
      return std::make_unique<LuaInteraction>(mod, *d, ctx);
  }
  return nullptr;
}

PluginDef make_plugin(const std::shared_ptr<ModState>& mod, const StageDecl& decl) {
  PluginDef def;
  def.info = decl.info;
  def.info.doc = (decl.info.doc.empty() ? std::string() : decl.info.doc + " ") + "(Lua, mod '" +
                 mod->name() + "')";
  def.create = LuaStageFactory{mod, decl.info.name};
  // Declarations only: the mod's runtime performs its resolver's calls.
  for (const auto& f : decl.functions) def.functions.push_back(InteractionFunction{.decl = f});
  return def;
}

bool registered_by(const PluginDef& def, const ModState& mod) {
  const auto* f = def.create.target<LuaStageFactory>();
  return f && f->mod.get() == &mod;
}

}  // namespace alloy::lua
