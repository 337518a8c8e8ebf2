#include "lua/mod_runtime.hpp"

#include <algorithm>
#include <cstdio>
#include <lua.hpp>
#include <optional>

#include "lua/file_watcher.hpp"
#include "lua/lua_bridge.hpp"
#include "lua/lua_stages.hpp"
#include "lua/native_bindings.hpp"
#include "runtime/contact_set.hpp"

namespace alloy::lua {

namespace fs = std::filesystem;

struct ModRuntime::Loaded {
  std::shared_ptr<ModState> state;
  std::vector<std::string> plugins;  // registered, in order
  std::vector<bool> handler_ok;      // per handler of the program: not disabled by an error
};

namespace {

bool same_property(const PropertyDef& a, const PropertyDef& b) {
  return a.kind == b.kind && a.enum_values == b.enum_values && a.unit == b.unit && a.min == b.min &&
         a.max == b.max && a.min_exclusive == b.min_exclusive;
}

bool is_lua_plugin(const PluginDef& def) {
  return def.create.target<LuaStageFactory>() != nullptr;
}

std::string kind_text(StageKind k) {
  return std::string(to_string(k));
}

}  // namespace

ModRuntime::ModRuntime(PluginRegistry& registry, ModRuntimeOptions options)
    : registry_(registry),
      options_(std::move(options)),
      self_(std::make_shared<ModRuntime*>(this)) {
  if (!options_.log)
    options_.log = [](const std::string& mod, const std::string& line) {
      std::fprintf(stderr, "[%s] %s\n", mod.c_str(), line.c_str());
    };
}

ModRuntime::~ModRuntime() {
  *self_ = nullptr;
  for (auto it = mods_.rbegin(); it != mods_.rend(); ++it)
    for (const auto& name : (*it)->plugins)
      if (const PluginDef* d = registry_.find(name); d && registered_by(*d, *(*it)->state))
        registry_.remove(name);
}

ModRuntime::Loaded* ModRuntime::find(const std::string& name) const {
  for (const auto& l : mods_)
    if (l->state->name() == name) return l.get();
  return nullptr;
}

std::vector<std::string> ModRuntime::loaded() const {
  std::vector<std::string> out;
  for (const auto& l : mods_) out.push_back(l->state->name());
  return out;
}

void ModRuntime::load(const std::string& name) {
  if (has(name)) return;
  LuaHost reader;
  for (const auto& dir : options_.mod_paths)
    if (fs::is_regular_file(dir / name / "mod.lua")) {
      std::vector<std::string> chain;
      load_manifest(read_manifest(reader, dir / name), chain);
      return;
    }
  std::string msg = "no mod named '" + name + "' on the mod path (";
  for (std::size_t i = 0; i < options_.mod_paths.size(); ++i)
    msg += (i ? ", " : "") + display_path(options_.mod_paths[i]);
  throw InputError(msg + ")");
}

void ModRuntime::load_folder(const fs::path& folder) {
  LuaHost reader;
  std::vector<std::string> chain;
  load_manifest(read_manifest(reader, folder), chain);
}

void ModRuntime::load(const Manifest& manifest) {
  std::vector<std::string> chain;
  load_manifest(manifest, chain);
}

void ModRuntime::load_manifest(const Manifest& m, std::vector<std::string>& chain) {
  if (has(m.name)) return;
  if (std::find(chain.begin(), chain.end(), m.name) != chain.end()) {
    std::string text;
    for (const auto& c : chain) text += c + " -> ";
    throw InputError(ErrorLocation{m.file, 0, ""}, "mod dependency cycle: " + text + m.name);
  }
  chain.push_back(m.name);
  // Dependencies first: a mod may queue on a dependency's resolver.
  std::vector<fs::path> paths = options_.mod_paths;
  fs::path parent = m.folder.lexically_normal();
  if (parent.filename().empty()) parent = parent.parent_path();
  paths.push_back(parent.parent_path().empty() ? fs::path(".") : parent.parent_path());
  for (const auto& dep : m.depends) {
    if (has(dep)) continue;
    bool found = false;
    LuaHost reader;
    for (const auto& dir : paths)
      if (fs::is_regular_file(dir / dep / "mod.lua")) {
        load_manifest(read_manifest(reader, dir / dep), chain);
        found = true;
        break;
      }
    if (!found)
      throw InputError(ErrorLocation{m.file, 0, ""}, "mod '" + m.name + "' depends on '" + dep +
                                                         "', which is not on the mod path");
  }
  chain.pop_back();
  if (m.runtime.empty()) return;  // parts and scenes only: nothing runs in the world

  auto state = std::make_shared<ModState>(m, paths, options_.budget, options_.log);
  std::unique_ptr<Program> p = state->load_program();
  try {
    validate(*state, *p);
  } catch (...) {
    state->release(*p);
    throw;
  }
  auto l = std::make_unique<Loaded>();
  l->state = state;
  Loaded& ref = *l;
  mods_.push_back(std::move(l));
  commit(ref, std::move(p), true);
  try {
    state->call_hook(state->program()->on_load, "on_load");
  } catch (...) {
    unload(m.name);
    throw;
  }
  if (watcher_) watcher_->add(m.folder);
  report({ModReport::Kind::Loaded, m.name,
          "mod '" + m.name + "' " + m.version + " loaded: " + std::to_string(ref.plugins.size()) +
              " stages, " + std::to_string(state->program()->handlers.size()) + " event handlers"});
}

void ModRuntime::validate(const ModState& mod, const Program& p) const {
  const PropertyRegistry& props = registry_.properties();
  const std::string file = display_path(mod.manifest().folder / mod.runtime_file());
  const ErrorLocation at_file{file, 0, ""};
  for (const auto& def : p.properties)
    if (auto id = props.find(def.name); id && !same_property(props.def(*id), def))
      throw InputError(at_file, "property '" + def.name + "' is already defined as " +
                                    std::string(to_string(props.def(*id).kind)) + " (unit '" +
                                    props.def(*id).unit + "') by '" + props.def(*id).owner +
                                    "'; mod '" + mod.name() + "' cannot define it differently");
  auto known_property = [&](const std::string& n) {
    if (props.find(n)) return true;
    return std::any_of(p.properties.begin(), p.properties.end(),
                       [&](const PropertyDef& d) { return d.name == n; });
  };
  auto lua_stage = [&](const std::string& n, StageKind kind) -> bool {
    if (const StageDecl* d = p.stage(n)) return d->info.kind == kind;
    const PluginDef* def = registry_.find(n);
    return def && is_lua_plugin(*def) && def->info.kind == kind;
  };
  for (const auto& s : p.stages) {
    const ErrorLocation& where = s.where;
    const std::string what = kind_text(s.info.kind) + " '" + s.info.name + "'";
    if (const PluginDef* def = registry_.find(s.info.name); def && !registered_by(*def, mod))
      throw InputError(where, what + ": the name is taken by " +
                                  (is_lua_plugin(*def) ? std::string("another mod's stage")
                                                       : std::string("a native plugin")));
    for (const auto* list : {&s.info.reads, &s.info.writes, &s.info.needs})
      for (const auto& n : *list)
        if (!known_property(n)) {
          std::vector<std::string> names = props.names();
          for (const auto& d : p.properties) names.push_back(d.name);
          std::string msg = what + ": unknown property '" + n + "'";
          if (auto near = closest_name(n, names); !near.empty())
            msg += " (did you mean '" + near + "'?)";
          throw InputError(where, msg);
        }
    for (const auto& d : s.info.derived)
      if (!native_derived_readable(registry_, d) && !lua_stage(d, StageKind::Derived))
        throw InputError(
            where, what + ": derived set '" + d + "' is not one a Lua stage can read (" +
                       native_contact_set_names(registry_) + ", or a derived set defined in Lua)");
    for (const auto& r : s.info.resolvers)
      if (!registry_.find(r) && !p.stage(r))
        throw InputError(where, what + ": unknown resolver '" + r + "'");
    if (s.info.kind == StageKind::Interaction) {
      const std::string& t = s.info.target;
      if (!native_resolver(registry_, t) && !lua_stage(t, StageKind::Resolver)) {
        std::string msg = what + ": target '" + t + "' is not a resolver Lua can queue on (" +
                          native_resolver_names(registry_) + ", or a resolver defined in Lua)";
        if (const PluginDef* def = registry_.find(t); !def) {
          std::vector<std::string> names = registry_.order();
          for (const auto& st : p.stages) names.push_back(st.info.name);
          if (auto near = closest_name(t, names); !near.empty())
            msg += " (did you mean '" + near + "'?)";
        }
        throw InputError(where, msg);
      }
    }
  }
  check_ownership(mod, p);
}

void ModRuntime::check_ownership(const ModState& mod, const Program& p) const {
  const PropertyRegistry& props = registry_.properties();
  const std::string& me = mod.name();
  const std::string file = display_path(mod.manifest().folder / mod.runtime_file());
  auto defines = [&](const std::string& name) {
    return std::any_of(p.properties.begin(), p.properties.end(),
                       [&](const PropertyDef& d) { return d.name == name; });
  };
  std::vector<std::string> granted;
  for (const WriteGrant& g : options_.grants) {
    if (g.mod != me) continue;
    for (const auto& name : g.properties) {
      if (!props.find(name) && !defines(name)) {
        std::string msg = "world: grants: mod '" + me + "' is granted property '" + name +
                          "', which does not exist";
        if (auto near = closest_name(name, props.names()); !near.empty())
          msg += " (did you mean '" + near + "'?)";
        throw InputError(g.where, msg);
      }
      granted.push_back(name);
    }
  }
  auto is_granted = [&](const std::string& name) {
    return std::find(granted.begin(), granted.end(), name) != granted.end();
  };
  // A property type belongs to whoever registered it first; a mod may not
  // define (and so come to think it may write) one of another's, unless the
  // scene granted it (two implementations of the same physics, swapped: each
  // defines the property it works on, the same way).
  for (std::size_t i = 0; i < p.properties.size(); ++i) {
    const auto id = props.find(p.properties[i].name);
    if (!id || owned_by_mod(props.def(*id), me) || is_granted(p.properties[i].name)) continue;
    const ErrorLocation where =
        i < p.property_where.size() ? p.property_where[i] : ErrorLocation{file, 0, ""};
    throw InputError(where, "mod.property '" + p.properties[i].name +
                                "': the property belongs to " + owner_text(props.def(*id)) +
                                "; mod '" + me +
                                "' cannot define it (read it as it is, define one of its own "
                                "under another name, or have the scene grant it)");
  }
  for (const auto& s : p.stages) {
    if (s.info.kind != StageKind::Resolver) continue;
    for (const auto& name : s.info.writes) {
      if (is_granted(name)) continue;
      if (const auto id = props.find(name)) {
        if (owned_by_mod(props.def(*id), me)) continue;
        throw InputError(s.where, "resolver '" + s.info.name + "' of mod '" + me + "' writes '" +
                                      name + "', which belongs to " + owner_text(props.def(*id)) +
                                      ": a mod's resolvers write only its own properties, "
                                      "unless the scene grants more (world { grants = { " +
                                      me + " = { \"" + name + "\" } } })");
      }
      // Not registered yet: one of this program's own (validate checked it exists).
    }
  }
}

void ModRuntime::commit(Loaded& l, std::unique_ptr<Program> p, bool first) {
  ModState& mod = *l.state;
  const Program* old = first ? nullptr : mod.program();
  for (const auto& def : p->properties) registry_.properties().add(def);

  std::vector<std::string> changed;  // plugins whose world stages go, and come back if still needed
  for (const auto& name : l.plugins) {
    const StageDecl* now = p->stage(name);
    const StageDecl* was = old ? old->stage(name) : nullptr;
    if (!now || (was && was->info.kind != now->info.kind)) {
      if (const PluginDef* d = registry_.find(name); d && registered_by(*d, mod))
        registry_.remove(name);
      changed.push_back(name);
    }
  }
  std::vector<std::string> plugins;
  for (const auto& d : p->stages) {
    const StageDecl* was = old ? old->stage(d.info.name) : nullptr;
    registry_.add(make_plugin(l.state, d));
    if (!was || !was->same_shape(d)) changed.push_back(d.info.name);
    plugins.push_back(d.info.name);
  }
  l.plugins = std::move(plugins);
  l.handler_ok.assign(p->handlers.size(), true);
  if (auto previous = mod.set_program(std::move(p))) mod.release(*previous);
  if (world_) {
    const World::QuietInputs one_input(*world_);  // the reload is the input (its event)
    for (const auto& name : changed) world_->plugin_changed(name);
  }
}

void ModRuntime::hold_impulses() {
  // Asked again whenever the collisions stage is a new one (a swap, or the
  // first time it exists): the demand then holds from the next advance, before
  // any contact that began now can end.
  if (world_->step_count() == impulses_checked_) return;  // once a step, not once an event
  impulses_checked_ = world_->step_count();
  bool wanted = false;
  for (const auto& l : mods_)
    if (!l->state->stopped() && l->state->program())
      for (const auto& [type, ref] : l->state->program()->handlers)
        wanted = wanted || type == "contact_ended" || type == "*";
  // The world's global contact set, found by what it is, not by its name.
  const ContactSet* set = nullptr;
  if (wanted)
    for (const auto& name : world_->active_stages()) {
      const PluginDef* def = world_->plugin_def(name);
      if (name.find('@') == std::string::npos && def && def->contacts)
        if ((set = dynamic_cast<const ContactSet*>(world_->stage(name)))) break;
    }
  const Stage* stage = set;
  if (stage == impulses_from_) return;
  impulses_from_ = stage;
  impulses_ = set ? set->demand_impulses() : ImpulseDemand{};
}

void ModRuntime::attach(World& world) {
  world_ = &world;
  std::weak_ptr<ModRuntime*> weak = self_;
  world.add_observer([weak](const Event& e) {
    if (auto p = weak.lock(); p && *p) (*p)->dispatch(e);
  });
  world.add_state_owner(StateOwner{[weak](Snapshot& out) {
                                     if (auto p = weak.lock(); p && *p) (*p)->save_states(out);
                                   },
                                   [weak](const Snapshot& in) -> std::function<void()> {
                                     if (auto p = weak.lock(); p && *p)
                                       return (*p)->prepare_states(in);
                                     return {};
                                   }});
}

void ModRuntime::save_states(Snapshot& out) {
  for (const auto& l : mods_)
    out.mod_states.push_back(
        {l->state->name(), l->state->manifest().version, l->state->save_state()});
}

namespace {

// New state tables not yet committed: freed if the restore is abandoned.
struct PreparedStates {
  std::vector<std::pair<std::shared_ptr<ModState>, int>> tables;
  bool committed = false;
  PreparedStates() = default;
  PreparedStates(const PreparedStates&) = delete;
  PreparedStates& operator=(const PreparedStates&) = delete;
  ~PreparedStates() {
    if (!committed)
      for (auto& [mod, ref] : tables) mod->drop_state(ref);
  }
};

}  // namespace

std::function<void()> ModRuntime::prepare_states(const Snapshot& in) {
  for (std::size_t i = 0; i < in.mod_states.size(); ++i) {
    const Snapshot::ModState& m = in.mod_states[i];
    if (!find(m.mod)) {
      std::string loaded;
      for (const auto& l : mods_) loaded += (loaded.empty() ? "" : ", ") + l->state->name();
      throw InputError("cannot restore the snapshot: it holds the state of mod '" + m.mod +
                       "' (version " + m.version +
                       "), which is not loaded (loaded: " + (loaded.empty() ? "none" : loaded) +
                       "); load the mod, or its state would be lost");
    }
    for (std::size_t j = 0; j < i; ++j)
      if (in.mod_states[j].mod == m.mod)
        throw InputError("cannot restore the snapshot: it holds the state of mod '" + m.mod +
                         "' twice");
  }
  auto prepared = std::make_shared<PreparedStates>();
  std::vector<std::pair<std::string, std::string>> notes;  // mod, text
  for (const auto& l : mods_) {
    const std::shared_ptr<ModState>& mod = l->state;
    const auto it = std::find_if(in.mod_states.begin(), in.mod_states.end(),
                                 [&](const Snapshot::ModState& m) { return m.mod == mod->name(); });
    int ref = -2;
    if (it == in.mod_states.end()) {
      ref = mod->prepare_fresh_state();
      notes.emplace_back(
          mod->name(),
          "mod '" + mod->name() + "': the snapshot holds no state of it; it starts with a new one");
    } else {
      bool migrated = false;
      ref = mod->prepare_state(it->bytes, it->version, &migrated);
      if (migrated)
        notes.emplace_back(mod->name(), "mod '" + mod->name() + "': state of version " +
                                            it->version + " migrated to " +
                                            mod->manifest().version + " by on_migrate");
      else if (it->version != mod->manifest().version)
        notes.emplace_back(mod->name(), "mod '" + mod->name() + "': state of version " +
                                            it->version + " restored as it is into version " +
                                            mod->manifest().version +
                                            " (the mod has no on_migrate)");
    }
    prepared->tables.emplace_back(mod, ref);
  }
  return [this, prepared, notes = std::move(notes)] {
    if (prepared->committed) return;
    prepared->committed = true;
    for (auto& [mod, ref] : prepared->tables) mod->commit_state(ref);
    for (const auto& [mod, text] : notes) report({ModReport::Kind::Note, mod, text});
  };
}

ModReport ModRuntime::reload(const std::string& name) {
  ModReport r;
  r.mod = name;
  Loaded* l = find(name);
  if (!l) {
    r.kind = ModReport::Kind::ReloadFailed;
    r.message = "mod '" + name + "' is not loaded";
    report(r);
    return r;
  }
  ModState& mod = *l->state;
  const Manifest before = mod.manifest();
  const bool was_stopped = mod.stopped();
  try {
    LuaHost reader;
    Manifest m = read_manifest(reader, before.folder);
    for (const auto& dep : m.depends)
      if (!has(dep) &&
          std::none_of(
              options_.mod_paths.begin(), options_.mod_paths.end(),
              [&](const fs::path& d) { return fs::is_regular_file(d / dep / "mod.lua"); }) &&
          !fs::is_regular_file(before.folder.parent_path() / dep / "mod.lua"))
        throw InputError(ErrorLocation{m.file, 0, ""}, "mod '" + name + "' depends on '" + dep +
                                                           "', which is not on the mod path");
    if (m.runtime.empty())
      throw InputError(ErrorLocation{m.file, 0, ""}, "mod.lua no longer names a runtime file");
    mod.set_manifest(m);
    if (was_stopped) mod.resume();
    std::unique_ptr<Program> p;
    try {
      p = mod.load_program();
      validate(mod, *p);
    } catch (...) {
      if (p) mod.release(*p);
      mod.set_manifest(before);
      if (was_stopped) mod.restop();
      throw;
    }
    commit(*l, std::move(p), false);
    r.kind = ModReport::Kind::Reloaded;
    r.message = "mod '" + name + "' reloaded: " + std::to_string(l->plugins.size()) + " stages, " +
                std::to_string(mod.program()->handlers.size()) + " event handlers";
    try {
      // After a stop the state table is new: the mod starts over.
      if (was_stopped)
        mod.call_hook(mod.program()->on_load, "on_load");
      else
        mod.call_hook(mod.program()->on_reload, "on_reload");
    } catch (const InputError& e) {
      r.message += "; but " + std::string(e.what());
      r.where = e.where();
    }
    if (world_)
      world_->view().emit(Event{.type = "mod_reloaded", .source = "mods", .text = r.message});
  } catch (const InputError& e) {
    r.kind = ModReport::Kind::ReloadFailed;
    r.where = e.where();
    r.message = "mod '" + name + "' was not reloaded, the old code keeps running: " + e.what();
    if (world_)
      world_->view().emit(Event{.type = "mod_reload_failed", .source = "mods", .text = r.message});
  }
  report(r);
  return r;
}

void ModRuntime::unload(const std::string& name) {
  Loaded* l = find(name);
  if (!l) return;
  for (const auto& other : mods_) {
    const auto& deps = other->state->manifest().depends;
    if (other.get() != l && std::find(deps.begin(), deps.end(), name) != deps.end())
      throw InputError("mod '" + name + "' cannot be unloaded: mod '" + other->state->name() +
                       "' depends on it");
  }
  ModState& mod = *l->state;
  if (mod.program() && !mod.stopped()) {
    try {
      mod.call_hook(mod.program()->on_unload, "on_unload");
    } catch (const InputError& e) {
      report({ModReport::Kind::Note, name, e.what(), e.where()});
    }
  }
  std::vector<std::string> plugins = l->plugins;
  for (const auto& p : plugins)
    if (const PluginDef* d = registry_.find(p); d && registered_by(*d, mod)) registry_.remove(p);
  if (world_)
    for (const auto& p : plugins) world_->plugin_changed(p);
  if (auto previous = mod.set_program(std::make_unique<Program>())) mod.release(*previous);
  std::erase_if(mods_, [&](const auto& x) { return x.get() == l; });
  report({ModReport::Kind::Unloaded, name, "mod '" + name + "' unloaded"});
}

void ModRuntime::watch() {
  if (!watcher_)
    watcher_ = std::make_unique<FileWatcher>(options_.poll_files ? FileWatcher::Mode::Polling
                                                                 : FileWatcher::Mode::Auto);
  for (const auto& l : mods_) watcher_->add(l->state->manifest().folder);
}

std::vector<ModReport> ModRuntime::poll() {
  if (watcher_) {
    std::vector<std::string> to_reload;
    for (const fs::path& file : watcher_->changed()) {
      if (file.extension() != ".lua") continue;
      for (const auto& l : mods_) {
        std::error_code ec;
        const fs::path folder = fs::absolute(l->state->manifest().folder, ec).lexically_normal();
        const auto rel = file.lexically_relative(folder);
        if (rel.empty() || *rel.begin() == "..") continue;
        const std::string& mod = l->state->name();
        const bool ours = rel == "mod.lua" ||
                          std::any_of(l->state->program()->files.begin(),
                                      l->state->program()->files.end(), [&](const std::string& f) {
                                        return fs::absolute(f, ec).lexically_normal() == file;
                                      });
        if (ours) {
          if (std::find(to_reload.begin(), to_reload.end(), mod) == to_reload.end())
            to_reload.push_back(mod);
        } else {
          report({ModReport::Kind::Note, mod,
                  display_path(file) +
                      " changed: scene and part files take effect when the scene is loaded again"});
        }
      }
    }
    for (const auto& m : to_reload) reload(m);
  }
  // What went wrong in the steps since the last poll.
  for (const auto& l : mods_) {
    ModState& mod = *l->state;
    if (mod.stopped() && !mod.stop_reported) {
      mod.stop_reported = true;
      report({ModReport::Kind::Stopped, mod.name(), mod.stop_reason()});
    }
    for (LuaStage* s : mod.stages())
      if (s->disabled() && !s->reported) {
        s->reported = true;
        report({ModReport::Kind::StageDisabled, mod.name(), s->disabled_reason()});
      }
  }
  std::vector<ModReport> out;
  out.swap(reports_);
  return out;
}

void ModRuntime::report(ModReport r) {
  // Loads are quiet; stage failures and stops were logged when their event
  // was published (dispatch), as they happened.
  if (r.kind != ModReport::Kind::Loaded && r.kind != ModReport::Kind::StageDisabled &&
      r.kind != ModReport::Kind::Stopped)
    options_.log(r.mod, r.message);
  reports_.push_back(std::move(r));
}

void ModRuntime::dispatch(const Event& e) {
  if (!world_) return;
  if (e.type == "stage_disabled" || e.type == "mod_stopped") {
    const std::string plugin = e.source.substr(0, e.source.find('@'));
    for (const auto& l : mods_)
      if (std::find(l->plugins.begin(), l->plugins.end(), plugin) != l->plugins.end())
        options_.log(l->state->name(), e.text);
  }
  hold_impulses();
  const PropertyStore& store = world_->store();
  for (const auto& lp : mods_) {
    Loaded& l = *lp;
    ModState& mod = *l.state;
    if (mod.stopped() || !mod.program()) continue;
    const auto& handlers = mod.program()->handlers;
    for (std::size_t h = 0; h < handlers.size(); ++h) {
      if (!l.handler_ok[h] || (handlers[h].first != "*" && handlers[h].first != e.type)) continue;
      lua_State* L = mod.state();
      StackGuard guard(L);
      // The event table is built outside a protected call: from the host's
      // reserve, so that a mod at the edge of its memory cannot make it fail.
      std::optional<MemoryBudget::HostScope> building(mod.host().memory());
      lua_rawgeti(L, LUA_REGISTRYINDEX, handlers[h].second);
      lua_createtable(L, 0, 10);
      lua_pushstring(L, e.type.c_str());
      lua_setfield(L, -2, "type");
      lua_pushstring(L, e.source.c_str());
      lua_setfield(L, -2, "source");
      lua_pushnumber(L, double(e.step));
      lua_setfield(L, -2, "step");
      lua_pushnumber(L, e.time);
      lua_setfield(L, -2, "time");
      for (auto [key, id] : {std::pair<const char*, ObjectId>{"a", e.a}, {"b", e.b}})
        if (store.alive(id)) {
          lua_pushnumber(L, id.index);
          lua_setfield(L, -2, key);
          lua_pushstring(L, store.describe(id).c_str());
          lua_setfield(L, -2, (std::string(key) + "_name").c_str());
        }
      if (!e.text.empty()) {
        lua_pushstring(L, e.text.c_str());
        lua_setfield(L, -2, "text");
      }
      lua_createtable(L, 0, int(e.values.size()));
      for (const auto& [k, v] : e.values) {
        lua_pushnumber(L, v);
        lua_setfield(L, -2, k.c_str());
      }
      lua_setfield(L, -2, "values");
      mod.push_state();
      building.reset();  // the handler's own allocations count as usual
      mod.begin_call(e.step);
      const ErrorLocation file{display_path(mod.manifest().folder / mod.runtime_file()), 0, ""};
      try {
        mod.host().call(2, 0, file);
        mod.end_call();
      } catch (const InputError& err) {
        mod.end_call();
        if (!handler_failed(l, h, err)) break;
        continue;
      }
      if (mod.stopped()) {  // stopped, and a pcall in the handler swallowed the error
        handler_failed(l, h, InputError(file, ""));
        break;
      }
    }
  }
}

bool ModRuntime::handler_failed(Loaded& l, std::size_t h, const InputError& raised) {
  ModState& mod = *l.state;
  mod.place_stop(raised.where());
  if (mod.stopped()) {
    // No stage publishes a stop in a handler (LuaStage::invoke does for its
    // own): say it now, and publish it with the next step's events.
    if (!mod.stop_event_sent) {
      mod.stop_event_sent = true;
      options_.log(mod.name(), mod.stop_reason());
      world_->view().emit(
          Event{.type = "mod_stopped", .source = "mods", .text = mod.stop_reason()});
    }
    return false;
  }
  const InputError err = mod.bounded(raised);
  l.handler_ok[h] = false;
  const std::string text = "event handler for '" + mod.program()->handlers[h].first + "' of mod '" +
                           mod.name() +
                           "' failed and is disabled until the mod is reloaded: " + err.what();
  options_.log(mod.name(), text);
  report({ModReport::Kind::StageDisabled, mod.name(), text, err.where()});
  return true;
}

std::vector<std::string> ModRuntime::plugins_of(const std::string& name) const {
  const Loaded* l = find(name);
  return l ? l->plugins : std::vector<std::string>{};
}

std::size_t ModRuntime::handlers_of(const std::string& name) const {
  const Loaded* l = find(name);
  return l && l->state->program() ? l->state->program()->handlers.size() : 0;
}

std::vector<std::string> ModRuntime::files_of(const std::string& name) const {
  const Loaded* l = find(name);
  return l && l->state->program() ? l->state->program()->files : std::vector<std::string>{};
}

bool ModRuntime::stopped(const std::string& name) const {
  const Loaded* l = find(name);
  return l && l->state->stopped();
}

std::string ModRuntime::stop_reason(const std::string& name) const {
  const Loaded* l = find(name);
  return l ? l->state->stop_reason() : "";
}

std::size_t ModRuntime::memory_of(const std::string& name) const {
  const Loaded* l = find(name);
  return l ? l->state->memory_used() : 0;
}

ModState::Output ModRuntime::output_of(const std::string& name) const {
  const Loaded* l = find(name);
  return l ? l->state->output_this_run() : ModState::Output{};
}

}  // namespace alloy::lua
