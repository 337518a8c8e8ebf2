#include "runtime/world.hpp"

#include <algorithm>
#include <cstdio>
#include <set>

namespace alloy {

/// An active stage and what the scheduler keeps about it.
struct World::Slot {
  StageInfo info;
  std::unique_ptr<Stage> stage;
  Resolver* resolver = nullptr;
  DerivedSet* derived = nullptr;
  Interaction* interaction = nullptr;
  std::vector<PropertyId> reads, writes;
  std::vector<Slot*> inputs;  // resolvers and derived sets whose output this stage reads
  int every = 1;
  std::size_t registry_rank = 0;
  std::size_t timing = 0;  // index into profile_.stages
  // Derived sets: input counters at the last update, and an output counter.
  std::vector<std::uint64_t> seen;
  bool updated_once = false;
  std::uint64_t output_version = 0;
  bool primed = false;  // has had its first derive / interact
  bool built = false;   // a resolver that has had its first build
};

// --- WorldView / ResolverAccess ----------------------------------------------

const PropertyRegistry& WorldView::properties() const { return world_.properties(); }
const PropertyStore& WorldView::store() const { return world_.store_; }
PropertyId WorldView::property(std::string_view name) const { return world_.properties().id(name); }
std::uint64_t WorldView::step() const { return world_.step_; }
double WorldView::time() const { return world_.time_; }
double WorldView::dt() const { return world_.def_.dt; }

void WorldView::emit(Event e) const {
  // step and time are stamped at publish: the step an event happened in, and
  // the simulated time at the end of that step, whichever phase emitted it.
  if (world_.current_stage_) e.source = *world_.current_stage_;
  world_.pending_.push_back(std::move(e));
}

// --- World -------------------------------------------------------------------

World::World(PluginRegistry& plugins, WorldDef def)
    : plugins_(plugins), def_(std::move(def)), store_(plugins.properties()) {
  if (!(def_.dt > 0) || !std::isfinite(def_.dt)) throw InputError("the time step dt must be a positive number");
  for (const auto& name : def_.plugins)
    if (!plugins_.find(name)) throw InputError("unknown plugin '" + name + "'");
  for (const auto& [name, n] : def_.every)
    if (n < 1) throw InputError("'every' for '" + name + "' must be at least 1");
  plugins_.properties().add({.name = "name", .kind = PropertyKind::String,
                             .doc = "unique scene name of the object", .owner = "runtime"});
}

World::~World() = default;

void World::set_dt(double dt) {
  if (started_) throw AccessError("the time step cannot change once the world has started");
  if (!(dt > 0) || !std::isfinite(dt)) throw InputError("the time step dt must be a positive number");
  def_.dt = dt;
}

ObjectId World::create(const std::string& name) {
  const ObjectId id = store_.create();
  if (!name.empty()) {
    try {
      store_.set(id, properties().id("name"), PropertyValue(name));
    } catch (...) {
      store_.destroy(id);
      throw;
    }
  }
  return id;
}

void World::destroy(ObjectId id) { store_.destroy(id); }

void World::set(ObjectId id, std::string_view property, const PropertyValue& value) {
  set(id, properties().id(property), value);
}
void World::set(ObjectId id, PropertyId property, const PropertyValue& value) {
  store_.set(id, property, value);
}
void World::remove(ObjectId id, std::string_view property) { store_.remove(id, properties().id(property)); }
PropertyValue World::get(ObjectId id, std::string_view property) const {
  return store_.get(id, properties().id(property));
}

void World::schedule(double time, ObjectId id, PropertyId property, const PropertyValue& value) {
  if (!std::isfinite(time) || time < 0)
    throw InputError(ErrorLocation{"", 0, store_.describe(id)}, "an input's time must be a number of seconds >= 0");
  PropertyValue v = store_.checked(id, property, value);
  auto at = std::upper_bound(inputs_.begin() + std::ptrdiff_t(next_input_), inputs_.end(), time,
                             [](double t, const ScheduledInput& in) { return t < in.time; });
  inputs_.insert(at, ScheduledInput{time, id, property, std::move(v)});
}

namespace {
std::string value_text(const PropertyValue& v, const PropertyDef& def, const PropertyStore& store) {
  char buf[96];
  return std::visit(
      [&](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, double>) return std::snprintf(buf, sizeof buf, "%g", x), buf;
        else if constexpr (std::is_same_v<T, std::int64_t>) return std::to_string(x);
        else if constexpr (std::is_same_v<T, bool>) return x ? "true" : "false";
        else if constexpr (std::is_same_v<T, Vec3>) return std::snprintf(buf, sizeof buf, "{%g, %g, %g}", x.x, x.y, x.z), buf;
        else if constexpr (std::is_same_v<T, Quat>)
          return std::snprintf(buf, sizeof buf, "{%g, %g, %g, %g}", x.w, x.x, x.y, x.z), buf;
        else if constexpr (std::is_same_v<T, std::string>) return "\"" + x + "\"";
        else if constexpr (std::is_same_v<T, ObjectId>) return x.is_null() ? "none" : store.describe(x);
        else if constexpr (std::is_same_v<T, RefList>) return std::to_string(x.size()) + " objects";
        else return def.enum_values.at(std::size_t(x.index));
      },
      v);
}
}  // namespace

void World::apply_inputs() {
  // Half a step of tolerance: an input at t = 1 s is applied before the step
  // that starts at 1 s, whatever the rounding of the accumulated time.
  while (next_input_ < inputs_.size() && inputs_[next_input_].time <= time_ + 0.5 * def_.dt) {
    const ScheduledInput& in = inputs_[next_input_++];
    if (!store_.alive(in.id)) continue;  // the player removed it meanwhile
    store_.set(in.id, in.property, in.value);
    const PropertyDef& def = properties().def(in.property);
    pending_.push_back(Event{.type = "input", .source = "schedule", .a = in.id,
                             .text = def.name + " = " + value_text(in.value, def, store_)});
  }
}

bool World::has_stage(std::string_view name) const {
  return std::any_of(slots_.begin(), slots_.end(), [&](const auto& s) { return s->info.name == name; });
}

Stage* World::stage(std::string_view name) {
  for (auto& s : slots_)
    if (s->info.name == name) return s->stage.get();
  return nullptr;
}

std::vector<std::string> World::active_stages() const {
  std::vector<std::string> out;
  for (const auto* group : {&resolvers_, &derived_, &interactions_})
    for (const Slot* s : *group) out.push_back(s->info.name);
  return out;
}

// --- the step ------------------------------------------------------------------

void World::start() {
  if (started_) return;
  started_ = true;
  sync_structure();
  // Prime the pipeline: derived data and queued commands from the initial
  // properties, so that the first advance integrates with the forces of t = 0.
  derive_phase();
  interact_phase();
  publish_phase();
  for (auto& s : slots_) s->primed = true;
  primed_ = true;
}

void World::step() {
  if (!started_) start();
  const double t0 = now_seconds();
  apply_inputs();
  sync_structure();
  const double t1 = now_seconds();
  advance_phase();
  store_.refresh();
  const double t2 = now_seconds();
  derive_phase();
  const double t3 = now_seconds();
  interact_phase();
  const double t4 = now_seconds();
  ++step_;
  publish_phase();
  const double t5 = now_seconds();
  profile_.phases.edits += t1 - t0;
  profile_.phases.advance += t2 - t1;
  profile_.phases.derive += t3 - t2;
  profile_.phases.interact += t4 - t3;
  profile_.phases.publish += t5 - t4;
  ++profile_.steps;
}

bool World::due(const Slot& s) const { return step_ % std::uint64_t(s.every) == 0; }

void World::advance_phase() {
  for (Slot* s : resolvers_) {
    StageTiming& timing = profile_.stages[s->timing];
    if (!due(*s)) {
      ++timing.skipped;
      continue;
    }
    current_stage_ = &s->info.name;
    ResolverAccess access(*this, s->info.name, s->writes);
    const double t = now_seconds();
    s->resolver->advance(access, def_.dt * s->every);
    timing.seconds += now_seconds() - t;
    ++timing.runs;
  }
  current_stage_ = nullptr;
  time_ += def_.dt;
}

bool World::inputs_changed(Slot& s) const {
  // One counter per read column (values and membership), per resolver read,
  // per derived set read. Any difference from the last update means recompute.
  std::size_t i = 0;
  bool changed = !s.updated_once;
  auto check = [&](std::uint64_t v) {
    if (i == s.seen.size()) s.seen.push_back(v), changed = true;
    else if (s.seen[i] != v) s.seen[i] = v, changed = true;
    ++i;
  };
  for (PropertyId p : s.reads) {
    const ColumnBase& c = store_.column(p);
    check(c.version());
    check(c.membership_version());
  }
  for (const Slot* in : s.inputs)
    check(in->resolver ? in->resolver->state_version() : in->output_version);
  return changed;
}

void World::derive_phase() {
  for (Slot* s : derived_) {
    StageTiming& timing = profile_.stages[s->timing];
    if (!due(*s) || !inputs_changed(*s)) {
      ++timing.skipped;
      continue;
    }
    current_stage_ = &s->info.name;
    const double t = now_seconds();
    s->derived->update(view());
    timing.seconds += now_seconds() - t;
    ++timing.runs;
    s->updated_once = true;
    ++s->output_version;
  }
  current_stage_ = nullptr;
}

void World::interact_phase() {
  for (Slot* s : interactions_) {
    StageTiming& timing = profile_.stages[s->timing];
    if (!due(*s)) {
      ++timing.skipped;
      continue;
    }
    current_stage_ = &s->info.name;
    const double t = now_seconds();
    s->interaction->apply(view());
    timing.seconds += now_seconds() - t;
    ++timing.runs;
  }
  current_stage_ = nullptr;
}

void World::publish_phase() {
  published_.swap(pending_);
  pending_.clear();
  for (Event& e : published_) {
    e.step = step_;
    e.time = time_;
  }
  for (const Event& e : published_)
    for (const auto& observer : observers_) observer(e);
}

// --- structure and activation ----------------------------------------------------

void World::sync_structure() {
  if (synced_ && seen_structure_ == store_.structure_version()) return;
  synced_ = true;
  // A resolver's build may give objects a column that makes another plugin
  // needed (gravity publishes `gravity`); settle that in a few rounds. Only
  // the first round rebuilds every resolver: later rounds see memberships that
  // resolvers wrote themselves, so only resolvers created in them are built.
  for (int round = 0; round < 4; ++round) {
    store_.refresh();
    activate_needed();
    seen_structure_ = store_.structure_version();
    for (Slot* s : resolvers_) {
      if (round > 0 && s->built) continue;
      s->built = true;
      current_stage_ = &s->info.name;
      ResolverAccess access(*this, s->info.name, s->writes);
      s->resolver->build(access);
    }
    store_.refresh();
    if (seen_structure_ == store_.structure_version()) break;
  }
  seen_structure_ = store_.structure_version();
  for (auto& s : slots_)
    if (!s->resolver) s->stage->on_structure_changed(view());
  current_stage_ = nullptr;
  if (primed_) prime_new_stages();
}

void World::prime_new_stages() {
  // A derived set or interaction created mid-run (a battery dropped into the
  // world) computes and queues from the present state now, so that its first
  // commands act in this step's advance, as at start().
  for (Slot* s : derived_) {
    if (s->primed) continue;
    current_stage_ = &s->info.name;
    inputs_changed(*s);  // record its input counters
    s->derived->update(view());
    s->updated_once = true;
    ++s->output_version;
  }
  for (Slot* s : interactions_) {
    if (s->primed) continue;
    current_stage_ = &s->info.name;
    s->interaction->apply(view());
  }
  for (auto& s : slots_) s->primed = true;
  current_stage_ = nullptr;
}

bool World::needed(const PluginDef& def) const {
  const StageInfo& info = def.info;
  if (!def_.plugins.empty() &&
      std::find(def_.plugins.begin(), def_.plugins.end(), info.name) == def_.plugins.end())
    return false;
  auto active = [&](const std::string& n) {
    return std::any_of(slots_.begin(), slots_.end(), [&](const auto& s) { return s->info.name == n; });
  };
  if (!info.target.empty() && !active(info.target)) return false;
  for (const auto& d : info.derived)
    if (!active(d)) return false;
  for (const auto& r : info.resolvers)
    if (!active(r)) return false;
  if (info.needs.empty()) return true;
  for (const auto& p : info.needs) {
    auto id = properties().find(p);
    if (id && store_.column(*id).count() > 0) return true;
  }
  return false;
}

void World::activate_needed() {
  // Resolvers first, then the derived sets and interactions that depend on
  // them; repeat until nothing new is needed (a derived set may read another).
  for (bool grew = true; grew;) {
    grew = false;
    for (StageKind kind : {StageKind::Resolver, StageKind::Derived, StageKind::Interaction}) {
      for (const auto& name : plugins_.order()) {
        const PluginDef* def = plugins_.find(name);
        if (def->info.kind != kind || has_stage(name) || !needed(*def)) continue;
        instantiate(*def);
        grew = true;
      }
    }
  }
  profile_.not_instantiated.clear();
  for (const auto& name : plugins_.order())
    if (!has_stage(name)) profile_.not_instantiated.push_back(name);
}

void World::instantiate(const PluginDef& def) {
  auto slot = std::make_unique<Slot>();
  slot->info = def.info;
  for (const auto& p : def.info.reads) slot->reads.push_back(properties().id(p));
  for (const auto& p : def.info.writes) slot->writes.push_back(properties().id(p));
  if (auto it = def_.every.find(def.info.name); it != def_.every.end()) slot->every = it->second;
  const auto& order = plugins_.order();
  slot->registry_rank = std::size_t(std::find(order.begin(), order.end(), def.info.name) - order.begin());

  static const PluginSettings kNoSettings;
  auto it = def_.settings.find(def.info.name);
  PluginContext ctx(*this, slot->info, it == def_.settings.end() ? kNoSettings : it->second);
  slot->stage = def.create(ctx);
  if (!slot->stage) throw AccessError("plugin '" + def.info.name + "' created nothing");
  switch (def.info.kind) {
    case StageKind::Resolver: slot->resolver = dynamic_cast<Resolver*>(slot->stage.get()); break;
    case StageKind::Derived: slot->derived = dynamic_cast<DerivedSet*>(slot->stage.get()); break;
    case StageKind::Interaction: slot->interaction = dynamic_cast<Interaction*>(slot->stage.get()); break;
  }
  if (!slot->resolver && !slot->derived && !slot->interaction)
    throw AccessError("plugin '" + def.info.name + "' created a stage of the wrong kind");
  for (const auto& n : def.info.derived)
    for (auto& s : slots_)
      if (s->info.name == n) slot->inputs.push_back(s.get());
  for (const auto& n : def.info.resolvers)
    for (auto& s : slots_)
      if (s->info.name == n) slot->inputs.push_back(s.get());
  slots_.push_back(std::move(slot));
  order_stages();
}

void World::order_stages() {
  // Resolvers: a writer of a column runs before its readers (so that a reader
  // sees this step's values), otherwise registry order. Derived sets: after the
  // derived sets they read. Interactions: registry order. All deterministic.
  auto topo = [&](std::vector<Slot*> group, auto before) {
    std::sort(group.begin(), group.end(),
              [](const Slot* a, const Slot* b) { return a->registry_rank < b->registry_rank; });
    std::vector<Slot*> out;
    std::set<Slot*> placed;
    while (out.size() < group.size()) {
      Slot* pick = nullptr;
      for (Slot* cand : group) {
        if (placed.count(cand)) continue;
        bool ready = true;
        for (Slot* other : group)
          if (other != cand && !placed.count(other) && before(other, cand) && !before(cand, other))
            ready = false;
        if (ready) {
          pick = cand;
          break;
        }
      }
      if (!pick)  // a cycle: fall back to registry order for the rest
        for (Slot* cand : group)
          if (!placed.count(cand)) {
            pick = cand;
            break;
          }
      placed.insert(pick);
      out.push_back(pick);
    }
    return out;
  };
  std::vector<Slot*> r, d, i;
  for (auto& s : slots_) (s->resolver ? r : s->derived ? d : i).push_back(s.get());
  resolvers_ = topo(r, [](const Slot* a, const Slot* b) {
    for (PropertyId w : a->writes)
      if (std::find(b->reads.begin(), b->reads.end(), w) != b->reads.end()) return true;
    return false;
  });
  derived_ = topo(d, [](const Slot* a, const Slot* b) {
    return std::find(b->inputs.begin(), b->inputs.end(), a) != b->inputs.end();
  });
  interactions_ = topo(i, [](const Slot*, const Slot*) { return false; });

  // Keep accumulated timings by name across re-ordering.
  std::vector<StageTiming> timings;
  for (const auto* group : {&resolvers_, &derived_, &interactions_})
    for (Slot* s : *group) {
      StageTiming t{s->info.name, s->info.kind};
      for (const auto& old : profile_.stages)
        if (old.name == s->info.name) t = old;
      s->timing = timings.size();
      timings.push_back(t);
    }
  profile_.stages = std::move(timings);
}

}  // namespace alloy
