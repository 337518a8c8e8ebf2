#include "runtime/world.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "runtime/contact_set.hpp"

namespace alloy {

/// An active stage and what the scheduler keeps about it.
struct World::Slot {
  StageInfo info;
  std::string instance;          // plugin name, or "plugin@area"
  int area = -1;                 // index into areas_, -1 for a global stage
  const Scope* scope = nullptr;  // what it acts on; null: every object
  std::unique_ptr<Stage> stage;
  Resolver* resolver = nullptr;
  DerivedSet* derived = nullptr;
  Interaction* interaction = nullptr;
  std::vector<PropertyId> reads, writes;
  std::vector<Slot*> inputs;  // resolvers and derived sets whose output this stage reads
  Slot* target = nullptr;     // an interaction's resolver (removed together with it)
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

const PropertyRegistry& WorldView::properties() const {
  return world_.properties();
}
const PropertyStore& WorldView::store() const {
  return world_.store_;
}
PropertyId WorldView::property(std::string_view name) const {
  return world_.properties().id(name);
}
std::uint64_t WorldView::step() const {
  return world_.step_;
}
double WorldView::time() const {
  return world_.time_;
}
double WorldView::dt() const {
  return world_.def_.dt;
}

int WorldView::every(std::string_view name) const {
  const auto it = world_.def_.every.find(name);
  return it == world_.def_.every.end() ? 1 : it->second;
}

void WorldView::emit(Event e) const {
  // step and time are stamped at publish: the step an event happened in, and
  // the simulated time at the end of that step, whichever phase emitted it.
  if (world_.current_stage_) e.source = *world_.current_stage_;
  world_.pending_.push_back(std::move(e));
}

// --- non-finite writes ---------------------------------------------------------

namespace detail {

void non_finite_write(ResolverAccess* access, std::uint32_t slot, PropertyId property,
                      const double* components, int count) {
  if (!access)
    throw AccessError("a column writer with no resolver behind it wrote a non-finite value");
  World& w = access->mutable_world_;
  const ObjectId id = w.freeze_slot(slot);
  if (id.is_null()) return;  // refused; one event per freeze
  static constexpr const char* kVec[] = {"x", "y", "z"};
  static constexpr const char* kQuat[] = {"w", "x", "y", "z"};
  Event e{.type = "non_finite",
          .source = access->stage_,
          .a = id,
          .text = w.properties().def(property).name};
  for (int i = 0; i < count; ++i)
    e.values.emplace_back(count == 1 ? "value" : count == 3 ? kVec[i] : kQuat[i], components[i]);
  w.pending_.push_back(std::move(e));
}

void out_of_scope_write(ResolverAccess* access, std::uint32_t slot) {
  // A frozen object is out of every scope, but a resolver may still reach it
  // through a reference (a hinge's body): its writes are dropped, not fatal.
  if (access && access->mutable_world_.frozen_slot(slot)) return;
  throw AccessError("a resolver of an area wrote object #" + std::to_string(slot) +
                    ", which is outside its area");
}

}  // namespace detail

ObjectId World::freeze_slot(std::uint32_t slot) {
  const ObjectId id = store_.id_at(slot);
  if (id.is_null() || frozen(id)) return {};
  frozen_.insert(std::upper_bound(frozen_.begin(), frozen_.end(), id,
                                  [](ObjectId a, ObjectId b) { return a.index < b.index; }),
                 id);
  frozen_changed_ = true;
  return id;
}

void ResolverAccess::refuse(std::uint32_t slot, const std::string& source, std::string text,
                            std::vector<std::pair<std::string, double>> values) {
  const ObjectId id = mutable_world_.freeze_slot(slot);
  if (id.is_null()) return;
  mutable_world_.pending_.push_back(Event{.type = "out_of_bounds",
                                          .source = source.empty() ? stage_ : source,
                                          .a = id,
                                          .values = std::move(values),
                                          .text = std::move(text)});
}

std::string frozen_message(const World& world, const Event& e) {
  if (e.type == "out_of_bounds") {
    // The source is the stage that gave the value; a mod's stage is named
    // with its mod, which chose the stage's name.
    std::string source = e.source;
    if (const PluginDef* d = world.plugin_def(e.source); d && !d->info.owner.empty())
      source = "mod '" + d->info.owner + "' (stage '" + e.source + "')";
    return "frozen: " + world.describe(e.a) + ": " + source + " " + e.text;
  }
  std::string value;
  char buf[32];
  for (const auto& [k, v] : e.values) {
    std::snprintf(buf, sizeof buf, "%g", v);
    value += (value.empty() ? "" : ", ") + std::string(buf);
  }
  if (e.values.size() > 1) value = "{" + value + "}";
  return "frozen: " + world.describe(e.a) + ": " + e.source + " wrote " + e.text + " = " + value;
}

bool World::frozen(ObjectId id) const {
  return std::find(frozen_.begin(), frozen_.end(), id) != frozen_.end();
}

bool World::frozen_slot(std::uint32_t slot) const {
  for (ObjectId id : frozen_)
    if (id.index == slot) return true;
  return false;
}

template <class Edit, class Describe>
auto World::as_input(Edit&& edit, Describe&& describe) {
  const bool outermost = input_depth_ == 0;
  ++input_depth_;
  struct Leave {
    int& depth;
    ~Leave() { --depth; }
  } leave{input_depth_};
  if constexpr (std::is_void_v<decltype(edit())>) {
    edit();
    if (outermost && !input_observers_.empty()) tell(describe());
  } else {
    auto result = edit();
    if (outermost && !input_observers_.empty()) tell(describe(result));
    return result;
  }
}

void World::unfreeze(ObjectId id) {
  as_input(
      [&] {
        store_.check_alive(id);
        if (std::erase(frozen_, id) > 0) frozen_changed_ = true;
      },
      [&] { return WorldInput{.kind = WorldInput::Kind::Unfreeze, .id = id}; });
}

// --- World -------------------------------------------------------------------

namespace {
void use_companions(const PluginRegistry& plugins,
                    std::map<std::string, std::string, std::less<>>& use);
}  // namespace

World::World(PluginRegistry& plugins, WorldDef def)
    : plugins_(plugins), def_(std::move(def)), store_(plugins.properties()) {
  if (!(def_.dt > 0) || !std::isfinite(def_.dt))
    throw InputError("the time step dt must be a positive number");
  for (const auto& name : def_.plugins)
    if (!plugins_.find(name)) throw InputError("unknown plugin '" + name + "'");
  for (const auto& [name, n] : def_.every)
    if (n < 1) throw InputError("'every' for '" + name + "' must be at least 1");
  plugins_.properties().add({.name = "name",
                             .kind = PropertyKind::String,
                             .doc = "unique scene name of the object",
                             .owner = "runtime"});
  for (const AreaDef& a : def_.areas) {
    if (a.name.empty()) throw InputError("an area needs a name");
    for (const Area& other : areas_)
      if (other.def.name == a.name) throw InputError("two areas are called '" + a.name + "'");
    for (const auto& p : a.plugins)
      if (!plugins_.find(p)) throw InputError("area '" + a.name + "': unknown plugin '" + p + "'");
    // One provider of a thing per scope, as globally: two rigid-body engines
    // listed in one area would both move its bodies.
    for (std::size_t i = 0; i < a.plugins.size(); ++i)
      for (std::size_t j = 0; j < i; ++j) {
        const std::string& what = plugins_.find(a.plugins[i])->info.provides;
        if (!what.empty() && what == plugins_.find(a.plugins[j])->info.provides)
          throw InputError("area '" + a.name + "': '" + a.plugins[j] + "' and '" + a.plugins[i] +
                           "' both provide '" + what + "'; list one");
      }
    areas_.push_back(Area{a, {}, {}});
  }
  for (const auto& [what, name] : def_.use) {
    const PluginDef* d = plugins_.find(name);
    if (!d) throw InputError("use: unknown plugin '" + name + "'");
    if (d->info.provides != what)
      throw InputError("use: '" + name + "' does not provide '" + what + "'");
  }
  use_companions(plugins_, def_.use);
}

World::~World() = default;

void World::set_dt(double dt) {
  if (started_) throw AccessError("the time step cannot change once the world has started");
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError("the time step dt must be a positive number");
  def_.dt = dt;
}

ObjectId World::create(const std::string& name) {
  return as_input(
      [&] {
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
      },
      [&](ObjectId id) {
        return WorldInput{.kind = WorldInput::Kind::Create, .id = id, .name = name};
      });
}

void World::destroy(ObjectId id) {
  as_input(
      [&] {
        store_.destroy(id);
        if (std::erase(frozen_, id) > 0) frozen_changed_ = true;
      },
      [&] { return WorldInput{.kind = WorldInput::Kind::Destroy, .id = id}; });
}

void World::set(ObjectId id, std::string_view property, const PropertyValue& value) {
  set(id, properties().id(property), value);
}
void World::set(ObjectId id, PropertyId property, const PropertyValue& value) {
  as_input([&] { store_.set(id, property, value); },
           [&] {
             // As the store keeps it (an integer given for a number is a number).
             return WorldInput{.kind = WorldInput::Kind::Set,
                               .id = id,
                               .property = properties().def(property).name,
                               .value = store_.get(id, property)};
           });
}
void World::remove(ObjectId id, std::string_view property) {
  as_input([&] { store_.remove(id, properties().id(property)); },
           [&] {
             return WorldInput{
                 .kind = WorldInput::Kind::Remove, .id = id, .property = std::string(property)};
           });
}
void World::check(ObjectId id) const {
  store_.check_alive(id);
  for (const auto& name : plugins_.order()) {
    const PluginDef* def = plugins_.find(name);
    if (!def->check) continue;
    try {
      def->check(*this, id);
    } catch (const InputError& e) {
      throw InputError(ErrorLocation{e.where().file, e.where().line, store_.describe(id)},
                       e.bare());
    }
  }
}

PropertyValue World::get(ObjectId id, std::string_view property) const {
  return store_.get(id, properties().id(property));
}

void World::schedule(double time, ObjectId id, PropertyId property, const PropertyValue& value) {
  if (!std::isfinite(time) || time < 0)
    throw InputError(ErrorLocation{"", 0, store_.describe(id)},
                     "an input's time must be a number of seconds >= 0");
  as_input(
      [&] {
        PropertyValue v = store_.checked(id, property, value);
        auto at =
            std::upper_bound(inputs_.begin() + std::ptrdiff_t(next_input_), inputs_.end(), time,
                             [](double t, const ScheduledInput& in) { return t < in.time; });
        return inputs_.insert(at, ScheduledInput{time, id, property, std::move(v)});
      },
      [&](auto it) {
        return WorldInput{.kind = WorldInput::Kind::Schedule,
                          .id = id,
                          .property = properties().def(property).name,
                          .value = it->value,
                          .time = time};
      });
}

void World::demand_impulses(bool on) {
  if (on == impulses_demanded_) return;
  as_input([&] { impulses_demanded_ = on; },
           [&] { return WorldInput{.kind = WorldInput::Kind::DemandImpulses, .value = on}; });
}

namespace {
std::string value_text(const PropertyValue& v, const PropertyDef& def, const PropertyStore& store) {
  char buf[96];
  return std::visit(
      [&](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, double>)
          return std::snprintf(buf, sizeof buf, "%g", x), buf;
        else if constexpr (std::is_same_v<T, std::int64_t>)
          return std::to_string(x);
        else if constexpr (std::is_same_v<T, bool>)
          return x ? "true" : "false";
        else if constexpr (std::is_same_v<T, Vec3>)
          return std::snprintf(buf, sizeof buf, "{%g, %g, %g}", x.x, x.y, x.z), buf;
        else if constexpr (std::is_same_v<T, Quat>)
          return std::snprintf(buf, sizeof buf, "{%g, %g, %g, %g}", x.w, x.x, x.y, x.z), buf;
        else if constexpr (std::is_same_v<T, std::string>)
          return "\"" + x + "\"";
        else if constexpr (std::is_same_v<T, ObjectId>)
          return x.is_null() ? "none" : store.describe(x);
        else if constexpr (std::is_same_v<T, RefList>)
          return std::to_string(x.size()) + " objects";
        else
          return def.enum_values.at(std::size_t(x.index));
      },
      v);
}
}  // namespace

void World::apply_inputs() {
  while (!swaps_.empty() && swaps_.front().time <= time_ + 0.5 * def_.dt) {
    ScheduledSwap sw = std::move(swaps_.front());
    swaps_.erase(swaps_.begin());
    ++input_depth_;  // the world's own input (the snapshot holds it): not told
    try {
      swap(sw.area, sw.from, sw.to);
    } catch (...) {
      --input_depth_;
      throw;
    }
    --input_depth_;
  }
  // Half a step of tolerance: an input at t = 1 s is applied before the step
  // that starts at 1 s, whatever the rounding of the accumulated time.
  while (next_input_ < inputs_.size() && inputs_[next_input_].time <= time_ + 0.5 * def_.dt) {
    const ScheduledInput& in = inputs_[next_input_++];
    if (!store_.alive(in.id)) continue;  // the player removed it meanwhile
    store_.set(in.id, in.property, in.value);
    const PropertyDef& def = properties().def(in.property);
    pending_.push_back(Event{.type = "input",
                             .source = "schedule",
                             .a = in.id,
                             .text = def.name + " = " + value_text(in.value, def, store_)});
  }
}

World::Slot* World::find_slot(std::string_view instance) const {
  for (const auto& s : slots_)
    if (s->instance == instance) return s.get();
  return nullptr;
}

bool World::has_stage(std::string_view name) const {
  return find_slot(name) != nullptr;
}

Stage* World::stage(std::string_view name) {
  Slot* s = find_slot(name);
  return s ? s->stage.get() : nullptr;
}

World::Slot* World::dependency(const Slot& of, std::string_view plugin) const {
  // A stage of an area depends on the area's own instance first, else the
  // global one; of the plugin of that name, or of one that provides it
  // (unless the stage names it in StageInfo::exact).
  const bool exact =
      std::find(of.info.exact.begin(), of.info.exact.end(), plugin) != of.info.exact.end();
  auto match = [&](const Slot& s) {
    return s.info.name == plugin || (!exact && s.info.provides == plugin);
  };
  if (of.area >= 0) {
    for (const auto& s : slots_)
      if (s->area == of.area && match(*s)) return s.get();
    // An area that lists its own provider but has not made it yet (nothing in
    // the area needed it so far) does not fall back on the global one: that
    // one leaves the area's objects out, so an area's gravity made before its
    // engine queued every pull on an engine that did not hold the bodies (a
    // ball rolling onto a table in an area with only static parts at load
    // flew on with no gravity and no friction). The stage waits for the
    // area's own instance instead.
    for (const auto& name : areas_[std::size_t(of.area)].def.plugins)
      if (const PluginDef* d = plugins_.find(name);
          d && (d->info.name == plugin || (!exact && d->info.provides == plugin)))
        return nullptr;
  }
  for (const auto& s : slots_)
    if (s->area < 0 && match(*s)) return s.get();
  return nullptr;
}

Stage* World::dependency_stage(const StageInfo& of, std::string_view area, std::string_view name,
                               std::string* instance) {
  Slot probe;
  probe.info.exact = of.exact;
  if (!area.empty())
    for (std::size_t i = 0; i < areas_.size(); ++i)
      if (areas_[i].def.name == area) probe.area = int(i);
  Slot* s = dependency(probe, name);
  if (s && instance) *instance = s->instance;
  return s ? s->stage.get() : nullptr;
}

std::vector<std::string> World::active_stages() const {
  std::vector<std::string> out;
  for (const auto* group : {&resolvers_, &derived_, &interactions_})
    for (const Slot* s : *group) out.push_back(s->instance);
  return out;
}

WorldView World::stage_view(std::string_view name) const {
  for (const auto& s : slots_)
    if (s->instance == name) return WorldView(*this, s->scope);
  return WorldView(*this);
}

// --- the step ------------------------------------------------------------------

void World::start() {
  if (started_) return;
  started_ = true;
  assign_areas();
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
  advanced_ = false;  // also after a step that threw
  if (!started_) start();
  const double t0 = clock();
  apply_inputs();
  const bool crossed = assign_areas();
  sync_structure();
  if (crossed) rescope();
  // Demanded from outside: held through this step's advance, taken again
  // each step from the contact sets there are now (a swap or a restore
  // makes new ones).
  impulse_demands_.clear();
  if (impulses_demanded_)
    for (const auto& s : slots_)
      if (const auto* contacts = dynamic_cast<const ContactSet*>(s->stage.get()))
        impulse_demands_.push_back(contacts->demand_impulses());
  const double t1 = clock();
  advance_phase();
  advanced_ = true;
  store_.refresh();
  // The advance moved bodies: put them in the areas of their new positions at
  // once, so that the derived sets, the interactions and the next advance see
  // each body under the stages of the area it is in. Handed over a step late,
  // a body that crossed would get its next force from its old area's resolver
  // at a position outside that area.
  if (assign_areas()) rescope();
  const double t2 = clock();
  derive_phase();
  const double t3 = clock();
  interact_phase();
  const double t4 = clock();
  advanced_ = false;
  ++step_;
  publish_phase();
  const double t5 = clock();
  profile_.phases.edits += t1 - t0;
  profile_.phases.advance += t2 - t1;
  profile_.phases.derive += t3 - t2;
  profile_.phases.interact += t4 - t3;
  profile_.phases.publish += t5 - t4;
  ++profile_.steps;
  if (!input_observers_.empty()) tell(WorldInput{.kind = WorldInput::Kind::Stepped});
}

bool World::due(const Slot& s) const {
  return step_ % std::uint64_t(s.every) == 0;
}

bool World::feeds(const Slot& s, std::uint64_t advance_step) const {
  // Commands queue up until their resolver advances: an interaction whose
  // target runs every n-th step queues only for the advance that performs it,
  // from the state just before it, or a load queued every step would act n
  // times over (the motor's rotor ran twice as fast with the rigid body every 2).
  return !s.target || advance_step % std::uint64_t(s.target->every) == 0;
}

void World::advance_phase() {
  for (Slot* s : resolvers_) {
    StageTiming& timing = profile_.stages[s->timing];
    if (!due(*s)) {
      ++timing.skipped;
      continue;
    }
    current_stage_ = &s->instance;
    ResolverAccess access(*this, s->instance, s->writes, s->scope);
    const double t = clock();
    s->resolver->advance(access, def_.dt * s->every);
    timing.seconds += clock() - t;
    ++timing.runs;
    if (stage_hook_) stage_hook_(s->instance);
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
    if (i == s.seen.size())
      s.seen.push_back(v), changed = true;
    else if (s.seen[i] != v)
      s.seen[i] = v, changed = true;
    ++i;
  };
  for (PropertyId p : s.reads) {
    const ColumnBase& c = store_.column(p);
    check(c.version());
    check(c.membership_version());
  }
  for (const Slot* in : s.inputs)
    check(in->resolver ? in->resolver->state_version() : in->output_version);
  check(s.scope ? s.scope->version() : 0);
  return changed;
}

bool World::wanted(const Slot& s) const {
  if (!s.derived->on_demand()) return true;
  const std::uint64_t next_advance = primed_ ? step_ + 1 : step_;
  bool read = false;
  for (const auto& r : slots_) {
    if (std::find(r->inputs.begin(), r->inputs.end(), &s) == r->inputs.end()) continue;
    read = true;
    if (r->resolver) return true;
    if (!due(*r)) continue;
    if (r->interaction ? feeds(*r, next_advance) : wanted(*r)) return true;
  }
  return !read;  // no stage reads it: whatever does (a tool), every step
}

void World::derive_phase() {
  for (Slot* s : derived_) {
    StageTiming& timing = profile_.stages[s->timing];
    if (!due(*s) || !wanted(*s) || !inputs_changed(*s)) {
      ++timing.skipped;
      continue;
    }
    current_stage_ = &s->instance;
    const double t = clock();
    s->derived->update(WorldView(*this, s->scope));
    timing.seconds += clock() - t;
    ++timing.runs;
    s->updated_once = true;
    ++s->output_version;
    if (stage_hook_) stage_hook_(s->instance);
  }
  current_stage_ = nullptr;
}

void World::interact_phase() {
  for (Slot* s : interactions_) {
    StageTiming& timing = profile_.stages[s->timing];
    if (!due(*s) || !feeds(*s, primed_ ? step_ + 1 : step_)) {
      ++timing.skipped;
      continue;
    }
    current_stage_ = &s->instance;
    const double t = clock();
    s->interaction->apply(WorldView(*this, s->scope));
    timing.seconds += clock() - t;
    ++timing.runs;
    if (stage_hook_) stage_hook_(s->instance);
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
  // Objects created or destroyed, memberships edited from outside or by
  // resolvers (the store counts the two apart), objects frozen or unfrozen,
  // stages swapped: every resolver rebuilds. Rebuilding, after a resolver's
  // own membership change, only the stages that read, write or need the
  // changed columns (store_.take_resolver_changes()) was tried and measured:
  // it changes results (the doorbell at dt = 1/60 rings, tests/coupled),
  // because a rebuild of the rigid body is not neutral (docs/performance.md,
  // "Harness overhead on rigid bodies"). It waits for that.
  const bool structural = !synced_ || seen_structure_ != store_.structure_version() ||
                          frozen_changed_ ||
                          seen_by_resolvers_ != store_.resolver_membership_version();
  if (!structural) return;
  synced_ = true;
  if (frozen_changed_ || !frozen_.empty()) {
    // Frozen objects leave every scope: global stages act on live_ (every
    // other object) while any is frozen, areas and their outsides drop them.
    frozen_changed_ = false;
    refresh_live();
    refresh_area_scopes();
    for (auto& s : slots_)
      if (s->area < 0)
        if (const PluginDef* d = plugins_.find(s->info.name)) s->scope = global_scope(*d);
  }
  // A resolver's build may give objects a column that makes another plugin
  // needed (gravity publishes `gravity`); settle that in a few rounds. Only
  // the first round rebuilds resolvers: later rounds see memberships that
  // resolvers wrote themselves, so only resolvers created in them are built.
  for (int round = 0; round < 4; ++round) {
    store_.refresh();
    activate_needed();
    const std::uint64_t before = store_.resolver_membership_version();
    for (Slot* s : resolvers_) {
      if (round > 0 && s->built) continue;
      s->built = true;
      current_stage_ = &s->instance;
      ResolverAccess access(*this, s->instance, s->writes, s->scope);
      s->resolver->build(access);
    }
    store_.refresh();
    if (store_.resolver_membership_version() == before) break;
  }
  store_.take_resolver_changes();  // seen
  seen_structure_ = store_.structure_version();
  seen_by_resolvers_ = store_.resolver_membership_version();
  for (auto& s : slots_)
    if (!s->resolver) s->stage->on_structure_changed(WorldView(*this, s->scope));
  current_stage_ = nullptr;
  if (primed_) prime_new_stages();
}

void World::prime_new_stages() {
  // A derived set or interaction created mid-run (a battery dropped into the
  // world) computes and queues from the present state now, so that its first
  // commands act in this step's advance, as at start(). Created after this
  // step's advance (a body crossed into an area during it), it is left to this
  // step's derive and interact phases, which run it anyway: primed here too,
  // its commands would be queued twice for the next advance.
  if (advanced_) {
    for (auto& s : slots_) s->primed = true;
    return;
  }
  for (Slot* s : derived_) {
    if (s->primed) continue;
    current_stage_ = &s->instance;
    inputs_changed(*s);  // record its input counters
    s->derived->update(WorldView(*this, s->scope));
    s->updated_once = true;
    ++s->output_version;
  }
  for (Slot* s : interactions_) {
    if (s->primed || !feeds(*s, step_)) continue;
    current_stage_ = &s->instance;
    s->interaction->apply(WorldView(*this, s->scope));
  }
  for (auto& s : slots_) s->primed = true;
  current_stage_ = nullptr;
}

namespace {
bool listed(const std::vector<std::string>& names, std::string_view n) {
  return std::find(names.begin(), names.end(), n) != names.end();
}
}  // namespace

bool World::chosen_globally(const PluginDef& def) const {
  const std::string& n = def.info.name;
  auto available = [&](const std::string& name) {
    return !listed(disabled_, name) &&
           (def_.plugins.empty() || listed(def_.plugins, name) || listed(enabled_, name));
  };
  if (!available(n)) return false;
  const std::string& what = def.info.provides;
  if (what.empty()) return true;
  // One provider of a thing per scope: the scene's choice, else the first registered.
  if (auto it = def_.use.find(what); it != def_.use.end()) return it->second == n;
  for (const auto& name : plugins_.order())
    if (plugins_.find(name)->info.provides == what && available(name)) return name == n;
  return false;
}

bool World::follows_area_provider(const PluginDef& def, int area) const {
  const StageInfo& info = def.info;
  if (info.kind != StageKind::Interaction || info.target.empty() || !chosen_globally(def))
    return false;
  const auto& list = areas_[std::size_t(area)].def.plugins;
  if (listed(list, info.name)) return false;
  // A target named exactly (ODE's contact joints name ODE) follows only that
  // engine; otherwise any provider of the target the area lists. The same for
  // a derived set it reads: electricity_from_collisions and
  // sound_from_collisions read `collisions`, which a Box2D area's
  // collisions.box2d provides there; without an instance of their own in the
  // area the global one read ODE's set, which leaves the area's parts out,
  // and a circuit inside a Box2D area never closed, silently (adv21).
  auto provided_here = [&](const std::string& what) {
    const bool exact = listed(info.exact, what);
    for (const auto& name : list)
      if (const PluginDef* d = plugins_.find(name);
          d && (d->info.name == what || (!exact && d->info.provides == what)))
        return true;
    return false;
  };
  if (provided_here(info.target)) return true;
  for (const auto& d : info.derived)
    if (provided_here(d)) return true;
  return false;
}

const Scope* World::global_scope(const PluginDef& def) {
  // A global stage leaves alone the areas that have their own instance of it
  // or their own provider of what it provides, and those where it follows the
  // area's own provider of its target (an instance of its own there).
  std::vector<int> excluded;
  for (std::size_t i = 0; i < areas_.size(); ++i) {
    if (follows_area_provider(def, int(i))) {
      excluded.push_back(int(i));
      continue;
    }
    for (const auto& p : areas_[i].def.plugins) {
      const PluginDef* d = plugins_.find(p);
      if (p == def.info.name ||
          (d && !def.info.provides.empty() && d->info.provides == def.info.provides)) {
        excluded.push_back(int(i));
        break;
      }
    }
  }
  if (excluded.empty()) return frozen_.empty() ? nullptr : &live_;
  Outside& o = outside_[def.info.name];
  o.areas = std::move(excluded);
  refresh_outside(o);
  return &o.scope;
}

bool World::needed_in(const PluginDef& def, int area) const {
  const StageInfo& info = def.info;
  const Scope* scope = nullptr;
  Slot probe;  // for dependency lookups in the right area
  probe.area = area;
  probe.info.exact = info.exact;
  if (area < 0) {
    if (!chosen_globally(def)) return false;
    if (auto it = outside_.find(info.name); it != outside_.end()) scope = &it->second.scope;
  } else {
    if (!listed(areas_[std::size_t(area)].def.plugins, info.name) &&
        !follows_area_provider(def, area))
      return false;
    scope = &areas_[std::size_t(area)].scope;
  }
  if (!info.target.empty() && !dependency(probe, info.target)) return false;
  for (const auto& d : info.derived)
    if (!dependency(probe, d)) return false;
  for (const auto& r : info.resolvers)
    if (!dependency(probe, r)) return false;
  if (info.needs.empty()) return true;
  for (const auto& p : info.needs) {
    auto id = properties().find(p);
    if (!id) continue;
    const ColumnBase& c = store_.column(*id);
    if (scope ? !scope->members_of(c).empty() : c.count() > 0) return true;
  }
  return false;
}

void World::activate_needed() {
  // Resolvers first, then the derived sets and interactions that depend on
  // them; repeat until nothing new is needed (a derived set may read another).
  // Global stages, then each area's, in the order the areas were given.
  for (bool grew = true; grew;) {
    grew = false;
    for (StageKind kind : {StageKind::Resolver, StageKind::Derived, StageKind::Interaction}) {
      for (int area = -1; area < int(areas_.size()); ++area) {
        for (const auto& name : plugins_.order()) {
          const PluginDef* def = plugins_.find(name);
          const std::string instance =
              area < 0 ? name : name + "@" + areas_[std::size_t(area)].def.name;
          if (def->info.kind != kind || has_stage(instance) || !needed_in(*def, area)) continue;
          instantiate(*def, area);
          grew = true;
        }
      }
    }
  }
  profile_.not_instantiated.clear();
  for (const auto& name : plugins_.order()) {
    bool any = has_stage(name);
    for (const auto& a : areas_) any = any || has_stage(name + "@" + a.def.name);
    if (!any) profile_.not_instantiated.push_back(name);
  }
}

void World::instantiate(const PluginDef& def, int area) {
  auto slot = std::make_unique<Slot>();
  slot->info = def.info;
  slot->area = area;
  slot->instance =
      area < 0 ? def.info.name : def.info.name + "@" + areas_[std::size_t(area)].def.name;
  slot->scope = area < 0 ? global_scope(def) : &areas_[std::size_t(area)].scope;
  for (const auto& p : def.info.reads) slot->reads.push_back(properties().id(p));
  for (const auto& p : def.info.writes) slot->writes.push_back(properties().id(p));
  if (auto it = def_.every.find(slot->instance); it != def_.every.end())
    slot->every = it->second;
  else if (auto it2 = def_.every.find(def.info.name); it2 != def_.every.end())
    slot->every = it2->second;
  const auto& order = plugins_.order();
  slot->registry_rank =
      std::size_t(std::find(order.begin(), order.end(), def.info.name) - order.begin());

  static const PluginSettings kNoSettings;
  const PluginSettings* settings = &kNoSettings;
  if (auto it = def_.settings.find(def.info.name); it != def_.settings.end())
    settings = &it->second;
  if (area >= 0) {
    const auto& own = areas_[std::size_t(area)].def.settings;
    if (auto it = own.find(def.info.name); it != own.end()) settings = &it->second;
  }
  PluginContext ctx(*this, slot->info, *settings,
                    area < 0 ? "" : areas_[std::size_t(area)].def.name);
  slot->stage = def.create(ctx);
  if (!slot->stage) throw AccessError("plugin '" + def.info.name + "' created nothing");
  switch (def.info.kind) {
    case StageKind::Resolver:
      slot->resolver = dynamic_cast<Resolver*>(slot->stage.get());
      break;
    case StageKind::Derived:
      slot->derived = dynamic_cast<DerivedSet*>(slot->stage.get());
      if (auto* set = dynamic_cast<ContactSet*>(slot->derived); set && !retired_.empty())
        for (auto r = retired_.begin(); r != retired_.end(); ++r)
          if (r->area == area && r->provides == slot->info.provides) {
            set->carry_over(dynamic_cast<const ContactSet&>(*r->stage));
            // Not primed: its first update comes after the new engine's
            // first advance. Before it, an engine that finds contacts only
            // while it steps (Box2D) has none, and would end every pair it
            // was handed, to begin them again a step later.
            slot->primed = true;
            retired_.erase(r);
            break;
          }
      break;
    case StageKind::Interaction:
      slot->interaction = dynamic_cast<Interaction*>(slot->stage.get());
      break;
  }
  if (!slot->resolver && !slot->derived && !slot->interaction)
    throw AccessError("plugin '" + def.info.name + "' created a stage of the wrong kind");
  for (const auto* names : {&def.info.derived, &def.info.resolvers})
    for (const auto& n : *names)
      if (Slot* in = dependency(*slot, n)) slot->inputs.push_back(in);
  if (!def.info.target.empty()) slot->target = dependency(*slot, def.info.target);
  slots_.push_back(std::move(slot));
  order_stages();
}

// --- areas and swaps ----------------------------------------------------------

bool AreaDef::contains(Vec3 p) const {
  const Vec3 d = p - center;
  if (radius > 0) return dot(d, d) <= radius * radius;
  if (half_extents == Vec3{}) return true;  // everywhere
  return std::abs(d.x) <= half_extents.x && std::abs(d.y) <= half_extents.y &&
         std::abs(d.z) <= half_extents.z;
}

std::string World::area_of(ObjectId id) const {
  if (!store_.alive(id) || id.index >= area_of_slot_.size() || area_of_slot_[id.index] < 0)
    return "";
  return areas_[std::size_t(area_of_slot_[id.index])].def.name;
}

void World::refresh_outside(Outside& o) const {
  Scope& sc = o.scope;
  sc.in_.assign(store_.slot_count(), 0);
  sc.slots_.clear();
  for (std::uint32_t slot = 0; slot < store_.slot_count(); ++slot) {
    if (store_.id_at(slot).is_null() || (!frozen_.empty() && frozen_slot(slot))) continue;
    const int a = slot < area_of_slot_.size() ? area_of_slot_[slot] : -1;
    if (a >= 0 && listed_area(o.areas, a)) continue;
    // A split object is in a global stage's scope only if every area its
    // referents are in is: the stage then acts on all of them.
    if (slot < split_.size() && std::any_of(split_[slot].begin(), split_[slot].end(), [&](int r) {
          return r >= 0 && listed_area(o.areas, r);
        }))
      continue;
    sc.in_[slot] = 1;
    sc.slots_.push_back(slot);
  }
  ++sc.version_;
}

const Column<Vec3>* World::position_column() const {
  const auto position = properties().find("position");
  const ColumnBase* pos = position ? store_.find_column(*position) : nullptr;
  return pos ? static_cast<const Column<Vec3>*>(pos) : nullptr;
}

bool World::place(std::uint32_t slot, int in, bool tell) {
  int& was = area_of_slot_[slot];
  if (in == was) return false;
  if (was >= 0) areas_[std::size_t(was)].left.push_back(slot);
  if (const ObjectId id = store_.id_at(slot); tell && id && (was >= 0 || in >= 0) && started_) {
    auto name = [&](int a) {
      return a < 0 ? std::string("(no area)") : areas_[std::size_t(a)].def.name;
    };
    pending_.push_back(Event{
        .type = "area_entered", .source = "world", .a = id, .text = name(was) + " -> " + name(in)});
  }
  was = in;
  return true;
}

bool World::assign_areas() {
  if (areas_.empty()) return false;
  const Column<Vec3>* column = position_column();
  const std::size_t n = store_.slot_count();
  bool changed = area_of_slot_.size() != n;
  area_of_slot_.resize(n, -1);
  for (Area& a : areas_) a.left.clear();
  // First the objects with a position, by where they are; then those without
  // (joints, springs, wires), by the objects they refer to.
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    if (!column || store_.id_at(slot).is_null() || !column->has(slot)) continue;
    int in = -1;
    for (std::size_t i = 0; i < areas_.size(); ++i)
      if (areas_[i].def.contains((*column)[slot])) {
        in = int(i);
        break;
      }
    changed |= place(slot, in, true);
  }
  changed |= assign_by_references(column);
  if (!changed) return false;
  refresh_area_scopes();
  return true;
}

std::vector<World::RefColumn> World::ref_columns() const {
  std::vector<RefColumn> out;
  for (PropertyId p = 0; p < properties().size(); ++p) {
    const PropertyKind kind = properties().def(p).kind;
    if (kind != PropertyKind::Ref && kind != PropertyKind::RefList) continue;
    // Presence, not members(): the member lists may not be refreshed yet
    // (at start, areas are assigned before the first refresh).
    if (const ColumnBase* c = store_.find_column(p))
      out.push_back({c, kind == PropertyKind::RefList});
  }
  return out;
}

void World::referent_areas(std::uint32_t slot, const Column<Vec3>* position,
                           const std::vector<RefColumn>& refs, std::vector<int>& out) const {
  out.clear();
  const ObjectId self = store_.id_at(slot);
  if (self.is_null() || !position) return;
  auto note = [&](ObjectId r) {
    // A referent without a position says nothing about where this object is;
    // a frozen one is in no scope and holds nothing (a joint to it is dropped
    // by the engine, as before areas knew references).
    if (r == self || !store_.alive(r) || !position->has(r.index) ||
        r.index >= area_of_slot_.size() || (!frozen_.empty() && frozen_slot(r.index)))
      return;
    const int a = area_of_slot_[r.index];
    if (std::find(out.begin(), out.end(), a) == out.end()) out.push_back(a);
  };
  for (const RefColumn& c : refs) {
    if (!c.column->has(slot)) continue;
    if (c.list)
      for (ObjectId r : static_cast<const Column<RefList>*>(c.column)->operator[](slot)) note(r);
    else
      note(static_cast<const Column<ObjectId>*>(c.column)->operator[](slot));
  }
  std::sort(out.begin(), out.end());
}

bool World::assign_by_references(const Column<Vec3>* position) {
  const std::size_t n = area_of_slot_.size();
  split_.resize(n);
  bool changed = false;
  const std::vector<RefColumn> refs = ref_columns();
  std::vector<int> found;
  auto name = [&](int a) {
    return a < 0 ? std::string("(no area)") : areas_[std::size_t(a)].def.name;
  };
  for (std::uint32_t slot = 0; slot < n; ++slot) {
    const ObjectId id = store_.id_at(slot);
    if (id && position && position->has(slot)) {  // placed by its position
      changed |= !split_[slot].empty();
      split_[slot].clear();
      continue;
    }
    referent_areas(slot, position, refs, found);
    const int in = found.size() == 1 ? found[0] : -1;
    if (found.size() < 2) found.clear();
    const bool was_split = !split_[slot].empty();
    if (found != split_[slot]) {
      changed = true;
      if (id && started_) {
        std::string text;
        for (int a : found) text += (text.empty() ? "" : ", ") + name(a);
        if (!found.empty())
          pending_.push_back(Event{.type = "area_split", .source = "world", .a = id, .text = text});
        else
          pending_.push_back(Event{.type = "area_entered",
                                   .source = "world",
                                   .a = id,
                                   .text = "(split) -> " + name(in)});
      }
      split_[slot] = found;
    }
    // A split's own event says where it went.
    changed |= place(slot, in, !was_split && found.empty());
  }
  return changed;
}

std::vector<std::string> World::split_areas(ObjectId id) const {
  std::vector<std::string> out;
  if (!store_.alive(id) || id.index >= split_.size()) return out;
  for (int a : split_[id.index]) out.push_back(a < 0 ? "" : areas_[std::size_t(a)].def.name);
  return out;
}

void World::refresh_area_scopes() {
  const std::size_t n = area_of_slot_.size();
  std::vector<std::uint8_t> frozen(n, 0);
  for (ObjectId id : frozen_)
    if (id.index < n) frozen[id.index] = 1;
  for (std::size_t i = 0; i < areas_.size(); ++i) {
    Scope& sc = areas_[i].scope;
    sc.in_.assign(n, 0);
    sc.slots_.clear();
    for (std::uint32_t slot = 0; slot < n; ++slot)
      if (area_of_slot_[slot] == int(i) && !frozen[slot])
        sc.in_[slot] = 1, sc.slots_.push_back(slot);
    ++sc.version_;
  }
  for (auto& [name, o] : outside_) refresh_outside(o);
}

void World::refresh_live() {
  const std::size_t n = store_.slot_count();
  live_.in_.assign(n, 0);
  live_.slots_.clear();
  for (std::uint32_t slot = 0; slot < n; ++slot)
    if (!store_.id_at(slot).is_null()) live_.in_[slot] = 1;
  for (ObjectId id : frozen_) live_.in_[id.index] = 0;
  for (std::uint32_t slot = 0; slot < n; ++slot)
    if (live_.in_[slot]) live_.slots_.push_back(slot);
  ++live_.version_;
}

void World::rescope() {
  // Objects crossed a border: stages of areas (and global stages kept out of
  // some areas) now act on other objects. Create what is newly needed, let
  // each scoped resolver drop what it published for objects that left, and
  // rebuild it from the properties; nothing else is touched.
  activate_needed();
  // All exits before any build, so that an object's new provider writes after
  // its old one erased, whichever runs first. The objects that left are no
  // longer in the resolver's scope: its access on exit reaches them and only them.
  Scope leaving;
  for (Slot* s : resolvers_) {
    if (!s->scope || s->area < 0) continue;
    const std::vector<std::uint32_t>& left = areas_[std::size_t(s->area)].left;
    if (left.empty()) continue;
    leaving.in_.assign(store_.slot_count(), 0);
    for (std::uint32_t slot : left) leaving.in_[slot] = 1;
    leaving.slots_ = left;
    ++leaving.version_;
    current_stage_ = &s->instance;
    ResolverAccess access(*this, s->instance, s->writes, &leaving);
    s->resolver->on_scope_exit(access, left);
  }
  for (Slot* s : resolvers_) {
    if (!s->scope) continue;
    current_stage_ = &s->instance;
    ResolverAccess access(*this, s->instance, s->writes, s->scope);
    s->resolver->build(access);
    s->built = true;
  }
  store_.refresh();
  for (auto& s : slots_)
    if (!s->resolver && s->scope) s->stage->on_structure_changed(WorldView(*this, s->scope));
  current_stage_ = nullptr;
  if (primed_) prime_new_stages();
}

void World::remove_with_dependents(Slot* root) {
  std::vector<Slot*> doomed{root};
  for (bool grew = true; grew;) {
    grew = false;
    for (auto& s : slots_) {
      if (listed_slot(doomed, s.get())) continue;
      bool depends = false;
      for (Slot* d : doomed) {
        depends = depends || listed_slot(s->inputs, d);
        depends = depends || (!s->info.target.empty() && dependency(*s, s->info.target) == d);
      }
      if (depends) doomed.push_back(s.get()), grew = true;
    }
  }
  std::erase_if(slots_, [&](const auto& s) { return listed_slot(doomed, s.get()); });
  order_stages();
}

void World::swap(std::string_view area, std::string_view from, std::string_view to) {
  as_input([&] { swap_now(area, from, to); },
           [&] {
             return WorldInput{.kind = WorldInput::Kind::Swap,
                               .area = std::string(area),
                               .from = std::string(from),
                               .to = std::string(to)};
           });
}

namespace {
/// Whether `p` is written against the engine `e` itself, so that it cannot run
/// with another provider of what `e` provides: it names `e` in its `exact`
/// list (ODE's `collisions` and contact joints name `rigid_body`), or it
/// depends on `e` by the engine's own name where that is not the name of what
/// it provides (`collisions.box2d` reads `rigid_body.box2d`).
bool bound_to(const PluginDef& p, const PluginDef& e) {
  const std::string& n = e.info.name;
  if (p.info.name == n) return false;
  if (listed(p.info.exact, n)) return true;
  if (e.info.provides.empty() || e.info.provides == n) return false;
  return p.info.target == n || listed(p.info.derived, n) || listed(p.info.resolvers, n);
}

/// An engine chosen with `use` brings what is written against it, as a swap
/// does: `use = { rigid_body = "rigid_body.box2d" }` means Box2D's contact set
/// too, unless the scene chose a provider of `collisions` itself.
void use_companions(const PluginRegistry& plugins,
                    std::map<std::string, std::string, std::less<>>& use) {
  std::vector<std::pair<std::string, std::string>> add;
  for (const auto& [what, name] : use) {
    const PluginDef* e = plugins.find(name);
    for (const auto& p : plugins.order()) {
      const PluginDef* q = plugins.find(p);
      if (!q->info.provides.empty() && !use.count(q->info.provides) && bound_to(*q, *e))
        add.emplace_back(q->info.provides, p);
    }
  }
  for (auto& [what, name] : add) use.emplace(what, name);
  // The other way round: a stage written against an engine needs that
  // engine. `use = { collisions = "collisions.box2d" }` alone brings Box2D's
  // rigid body (without it the contact set would stay out and every body
  // fall through the floor, silently); a scene that chose another engine
  // for the same thing is told so.
  std::vector<std::pair<std::string, std::string>> engines;
  for (const auto& [what, name] : use) {
    const PluginDef* d = plugins.find(name);
    if (!d) continue;
    for (const auto& e_name : plugins.order()) {
      const PluginDef* e = plugins.find(e_name);
      if (e->info.provides.empty() || !bound_to(*d, *e)) continue;
      const auto chosen = use.find(e->info.provides);
      if (chosen != use.end() && chosen->second != e_name)
        throw InputError("use: '" + name + "' is written against '" + e_name +
                         "', but the scene uses '" + chosen->second + "' for '" + e->info.provides +
                         "'");
      engines.emplace_back(e->info.provides, e_name);
    }
  }
  for (auto& [what, name] : engines) use.emplace(what, name);
}
}  // namespace

void World::swap_now(std::string_view area, std::string_view from, std::string_view to) {
  const PluginDef* f = plugins_.find(from);
  const PluginDef* t = plugins_.find(to);
  if (!f) throw InputError("swap: unknown plugin '" + std::string(from) + "'");
  if (!t)
    throw InputError("swap: unknown plugin '" + std::string(to) + "'" + [&] {
      auto n = closest_name(to, plugins_.order());
      return n.empty() ? std::string() : " (did you mean '" + n + "'?)";
    }());
  if (f->info.kind != t->info.kind)
    throw InputError("swap: '" + std::string(from) + "' is a " +
                     std::string(to_string(f->info.kind)) + " and '" + std::string(to) + "' a " +
                     std::string(to_string(t->info.kind)));
  // A swap replaces one implementation of a thing by another: gravity swapped
  // for a rigid body would run two engines on the same bodies (each moved
  // them, at twice their speed), so the two must provide the same thing (or,
  // plugins that declare nothing, the new one nothing either).
  const auto provided = [](const PluginDef& d) {
    return d.info.provides.empty() ? std::string("nothing") : "'" + d.info.provides + "'";
  };
  if (f->info.provides != t->info.provides)
    throw InputError("swap: '" + std::string(from) + "' provides " + provided(*f) + " and '" +
                     std::string(to) + "' provides " + provided(*t) +
                     "; a swap replaces one provider of a thing by another");
  // And the one swapped out must be the one running there, else the event
  // would tell of a swap that changed nothing. A swap to the one already
  // running (a contact set that came along with its engine) is nothing.
  if (area.empty() && !f->info.provides.empty() && !chosen_globally(*f)) {
    if (chosen_globally(*t)) return;
    const auto chosen = def_.use.find(f->info.provides);
    throw InputError("swap: '" + std::string(from) + "' does not run here" +
                     (chosen != def_.use.end()
                          ? " ('" + chosen->second + "' is the " + f->info.provides + ")"
                          : std::string()));
  }
  // A stage written against an engine (Box2D's contact set) swapped in where
  // that engine does not run would stay out, and bodies would fall through
  // one another unseen: refused, saying what to swap instead.
  if (area.empty())
    for (const auto& e_name : plugins_.order()) {
      const PluginDef* e = plugins_.find(e_name);
      if (e->info.provides.empty() || e == f || !bound_to(*t, *e)) continue;
      const auto chosen = def_.use.find(e->info.provides);
      const std::string current = chosen != def_.use.end() ? chosen->second : e->info.provides;
      if (current != e_name)
        throw InputError("swap: '" + std::string(to) + "' is written against '" + e_name +
                         "', which does not run here ('" + current + "' is the " +
                         e->info.provides + "); swap '" + current + "' to '" + e_name +
                         "' and its contact set comes along");
    }
  // The stages written against the engine swapped out go with it, and the new
  // engine brings its own (a rigid body's contact set: ODE's `collisions`
  // needs ODE, `collisions.box2d` needs Box2D). Swapping the rigid body alone
  // would otherwise leave the scope with no contact set, and electricity,
  // sound and the mods' contact handlers would go quiet.
  auto counterpart = [&](const PluginDef& p) -> const PluginDef* {
    if (p.info.provides.empty()) return nullptr;
    for (const auto& name : plugins_.order()) {
      const PluginDef* q = plugins_.find(name);
      if (q->info.kind == p.info.kind && q->info.provides == p.info.provides && bound_to(*q, *t))
        return q;
    }
    return nullptr;
  };
  std::vector<std::pair<std::string, std::string>> along;  // (companion out, companion in)
  std::vector<Slot*> old;
  if (area.empty()) {
    for (const auto& name : plugins_.order()) {
      const PluginDef* p = plugins_.find(name);
      if (!bound_to(*p, *f) || !chosen_globally(*p)) continue;
      if (const PluginDef* q = counterpart(*p)) along.emplace_back(p->info.name, q->info.name);
    }
    auto swap_global = [&](const std::string& out, const std::string& in) {
      if (Slot* s = find_slot(out)) old.push_back(s);
      std::erase(disabled_, in);
      if (!listed(disabled_, out)) disabled_.push_back(out);
      if (!def_.plugins.empty() && !listed(def_.plugins, in) && !listed(enabled_, in))
        enabled_.push_back(in);
      const PluginDef* d = plugins_.find(in);
      if (!d->info.provides.empty()) def_.use[d->info.provides] = in;
    };
    swap_global(std::string(from), std::string(to));
    for (const auto& [out, in] : along) swap_global(out, in);
  } else {
    auto a = std::find_if(areas_.begin(), areas_.end(),
                          [&](const Area& x) { return x.def.name == area; });
    if (a == areas_.end()) throw InputError("swap: no area is called '" + std::string(area) + "'");
    std::vector<std::string>& list = a->def.plugins;
    auto it = std::find(list.begin(), list.end(), from);
    if (it == list.end())
      throw InputError("swap: area '" + std::string(area) + "' has no plugin '" +
                       std::string(from) + "'");
    *it = std::string(to);
    const std::string at = "@" + std::string(area);
    if (Slot* s = find_slot(std::string(from) + at)) old.push_back(s);
    // The area's list names its stages: the old engine's own are replaced by
    // the new engine's counterparts or dropped (ODE's contact joints have none
    // on Box2D), and the new engine's own that the area lacks are added.
    std::vector<std::string> kept;
    for (const std::string& name : list) {
      const PluginDef* p = plugins_.find(name);
      if (!p || !bound_to(*p, *f)) {
        kept.push_back(name);
        continue;
      }
      if (Slot* s = find_slot(name + at)) old.push_back(s);
      const PluginDef* q = counterpart(*p);
      along.emplace_back(name, q ? q->info.name : std::string("nothing"));
      if (q && !listed(kept, q->info.name)) kept.push_back(q->info.name);
    }
    for (const auto& name : plugins_.order()) {
      const PluginDef* q = plugins_.find(name);
      if (!bound_to(*q, *t) || listed(kept, name)) continue;
      const bool provided = !q->info.provides.empty() &&
                            std::any_of(kept.begin(), kept.end(), [&](const std::string& k) {
                              const PluginDef* d = plugins_.find(k);
                              return d && d->info.provides == q->info.provides;
                            });
      if (provided) continue;
      kept.push_back(name);
      along.emplace_back("nothing", name);
    }
    list = std::move(kept);
  }
  // The contact sets going out hand their pairs to the ones coming in (at
  // their creation, in sync_structure), so that the swap itself begins and
  // ends no contact.
  // Emptied however the swap ends (a new engine that fails to build throws
  // out of sync_structure below): a contact set made later (a body entering
  // an area) must not take pairs from a swap that did not happen.
  struct ClearRetired {
    std::vector<Retired>& list;
    ~ClearRetired() { list.clear(); }
  } clear_retired{retired_};
  retired_.clear();
  if (started_)
    for (Slot* s : old)
      if (s->derived && dynamic_cast<ContactSet*>(s->derived)) {
        s->derived = nullptr;
        retired_.push_back({s->area, s->info.provides, std::move(s->stage)});
      }
  // Removing one slot may remove another (a dependent): look each up again.
  for (Slot* s : old)
    if (std::any_of(slots_.begin(), slots_.end(), [&](const auto& x) { return x.get() == s; }))
      remove_with_dependents(s);
  // Global scopes depend on which areas provide what; recompute them.
  for (auto& s : slots_)
    if (s->area < 0) s->scope = global_scope(*plugins_.find(s->info.name));
  std::string text = std::string(from) + " -> " + std::string(to) +
                     (area.empty() ? std::string(" (everywhere)") : " in " + std::string(area));
  if (!along.empty()) {
    text += "; with";
    for (std::size_t i = 0; i < along.size(); ++i)
      text += (i ? ", " : " ") + along[i].first + " -> " + along[i].second;
  }
  pending_.push_back(Event{.type = "resolver_swapped", .source = "world", .text = std::move(text)});
  if (started_) {
    synced_ = false;
    sync_structure();  // instantiate the new stage and its dependents, build, prime
  }
}

std::vector<std::string> World::plugin_changed(std::string_view plugin) {
  return as_input([&] { return plugin_changed_now(plugin); },
                  [&](const std::vector<std::string>&) {
                    return WorldInput{.kind = WorldInput::Kind::PluginChanged,
                                      .name = std::string(plugin)};
                  });
}

std::vector<std::string> World::plugin_changed_now(std::string_view plugin) {
  std::vector<std::string> before = active_stages();
  for (;;) {
    auto it = std::find_if(slots_.begin(), slots_.end(),
                           [&](const auto& s) { return s->info.name == plugin; });
    if (it == slots_.end()) break;
    remove_with_dependents(it->get());
  }
  std::vector<std::string> after = active_stages();
  std::erase_if(before, [&](const std::string& n) { return listed(after, n); });
  // A slot whose plugin already left the registry (a mod unloading several
  // plugins, told one at a time) keeps its scope: its own call removes it.
  for (auto& s : slots_)
    if (const PluginDef* d = plugins_.find(s->info.name); d && s->area < 0)
      s->scope = global_scope(*d);
  if (started_) {
    synced_ = false;
    sync_structure();
  }
  return before;
}

void World::schedule_swap(double time, std::string area, std::string from, std::string to) {
  if (!std::isfinite(time) || time < 0)
    throw InputError("a swap's time must be a number of seconds >= 0");
  if (!plugins_.find(from)) throw InputError("swap: unknown plugin '" + from + "'");
  if (!plugins_.find(to)) throw InputError("swap: unknown plugin '" + to + "'");
  if (!area.empty() &&
      std::none_of(areas_.begin(), areas_.end(), [&](const Area& a) { return a.def.name == area; }))
    throw InputError("swap: no area is called '" + area + "'");
  auto at = std::upper_bound(swaps_.begin(), swaps_.end(), time,
                             [](double t, const ScheduledSwap& s) { return t < s.time; });
  as_input(
      [&] {
        swaps_.insert(at, ScheduledSwap{time, area, from, to});
      },
      [&] {
        return WorldInput{.kind = WorldInput::Kind::ScheduleSwap,
                          .time = time,
                          .area = area,
                          .from = from,
                          .to = to};
      });
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
      StageTiming t{s->instance, s->info.kind};
      for (const auto& old : profile_.stages)
        if (old.name == s->instance) t = old;
      s->timing = timings.size();
      timings.push_back(t);
    }
  profile_.stages = std::move(timings);
  report_held_stages();
}

void World::report_held_stages() {
  // A held input is a zero-order hold: for a position-dependent force (the
  // magnetic loads held while the rigid body runs every step) it lags the
  // motion and does work no field pays (the motor ran away at 1/240 s with
  // magnetic_forces every 2nd step), and an induced EMF sent once in n
  // advances is absent from the others (docs/performance.md, "Session 21").
  auto report = [&](const Slot& held, const Slot& by, const char* what, const char* between) {
    const std::string key = held.instance + ">" + by.instance;
    if (!held_reported_.insert(key).second) return;
    pending_.push_back(
        Event{.type = "held_stage",
              .source = "world",
              .values = {{"every", double(held.every)}, {"reader_every", double(by.every)}},
              .text = by.instance + " " + what + " " + held.instance + ", which runs every " +
                      std::to_string(held.every) + " steps: " + between +
                      "; a held force does work no field pays (docs/performance.md)"});
  };
  for (const auto& s : slots_) {
    for (const Slot* in : s->inputs)
      if (in->derived && in->every > s->every)
        report(*in, *s, "reads", "in between it reads the output held, not recomputed");
    if (s->interaction && s->target && s->every > s->target->every)
      report(*s, *s->target, "is commanded by", "in between its advances get no commands from it");
  }
}

// --- snapshots -------------------------------------------------------------------

Snapshot::Size Snapshot::size(const Snapshot* base) const {
  Size z;
  for (const Column& c : columns) {
    const std::size_t n = c.values->bytes() + c.property.size() + sizeof(Column);
    z.bytes += n;
    ++z.columns;
    if (const Column* b = base ? base->column(c.property) : nullptr; b && b->values == c.values) {
      z.shared_bytes += n;
      ++z.shared_columns;
    }
  }
  z.bytes += objects.generations.size() * (sizeof(std::uint32_t) + 1 + sizeof(std::string));
  for (const auto& n : objects.names) z.bytes += n.size() > 15 ? n.capacity() : 0;
  z.bytes += objects.free_slots.size() * sizeof(std::uint32_t) + area_of_slot.size() * sizeof(int);
  z.bytes += frozen.size() * sizeof(ObjectId) + inputs.size() * sizeof(Input) +
             swaps.size() * sizeof(Swap);
  for (const auto& st : stage_states) z.bytes += st.bytes.size() + st.stage.size();
  for (const auto& m : mod_states) z.bytes += m.bytes.size() + m.mod.size() + m.version.size();
  return z;
}

const Snapshot::Column* Snapshot::column(std::string_view property) const {
  auto it = std::lower_bound(columns.begin(), columns.end(), property,
                             [](const Column& c, std::string_view p) { return c.property < p; });
  return it != columns.end() && it->property == property ? &*it : nullptr;
}

std::vector<Snapshot::StageState> World::stage_states() const {
  std::vector<Snapshot::StageState> out;
  for (const auto* group : {&resolvers_, &derived_, &interactions_})
    for (const Slot* s : *group) {
      StateWriter w;
      if (s->stage->save_state(w)) out.push_back({s->instance, w.take()});
    }
  return out;
}

Snapshot World::snapshot(const Snapshot* base) const {
  Snapshot s;
  s.step = step_;
  s.time = time_;
  s.dt = def_.dt;
  s.started = started_;
  s.resync =
      started_ && (!synced_ || frozen_changed_ || seen_structure_ != store_.structure_version() ||
                   seen_by_resolvers_ != store_.resolver_membership_version());
  s.objects = store_.objects();
  s.lineage = store_.lineage();
  const bool delta = base && base->lineage == s.lineage;
  for (const std::string& name : properties().names()) {  // sorted
    const PropertyId id = *properties().find(name);
    const ColumnBase* c = store_.find_column(id);
    if (!c) continue;
    Snapshot::Column col{name, properties().def(id).kind, nullptr, c->version(),
                         c->membership_version()};
    if (const Snapshot::Column* b = delta ? base->column(name) : nullptr;
        b && b->kind == col.kind && b->version == col.version &&
        b->membership_version == col.membership_version &&
        // create() grows a column by a slot without moving its counters
        b->values->presence().size() == c->presence().size())
      col.values = b->values;  // unchanged since the base: shared
    else
      col.values = c->clone();
    s.columns.push_back(std::move(col));
  }
  s.frozen = frozen_;
  s.area_of_slot = area_of_slot_;
  for (const Area& a : areas_) s.area_plugins.push_back(a.def.plugins);
  s.disabled = disabled_;
  s.enabled = enabled_;
  for (const auto& [what, plugin] : def_.use) s.use.emplace(what, plugin);
  s.stages = active_stages();
  s.stage_states = stage_states();
  for (std::size_t i = next_input_; i < inputs_.size(); ++i) {
    const ScheduledInput& in = inputs_[i];
    s.inputs.push_back({in.time, in.id, properties().def(in.property).name, in.value});
  }
  for (const ScheduledSwap& sw : swaps_) s.swaps.push_back({sw.time, sw.area, sw.from, sw.to});
  for (const StateOwner& o : state_owners_)
    if (o.save) o.save(s);
  return s;
}

void World::sync() {
  as_input([&] { sync_now(); }, [] { return WorldInput{.kind = WorldInput::Kind::Sync}; });
}

void World::sync_now() {
  if (!started_) return;  // start() builds everything from the properties
  synced_ = false;
  sync_structure();
  // Then build everything afresh, as a restore of this moment would: the
  // snapshot taken now and the world that goes on are one and the same. The
  // events not yet published (a swap's) and the last step's stay: restore
  // drops them, as they belong to the run that took the snapshot.
  std::vector<Event> pending = std::move(pending_), published = std::move(published_);
  restore(snapshot());
  pending_ = std::move(pending), published_ = std::move(published);
}

void World::restore(const Snapshot& s) {
  as_input([&] { restore_now(s); },
           [&] { return WorldInput{.kind = WorldInput::Kind::Restore, .snapshot = &s}; });
}

void World::restore_now(const Snapshot& s) {
  // Everything that can be checked before the world changes is checked first:
  // a snapshot that does not fit leaves the world as it was.
  auto refuse = [](const std::string& what) {
    throw InputError("cannot restore the snapshot: " + what);
  };
  if (!(s.dt > 0) || !std::isfinite(s.dt)) refuse("its time step is not a positive number");
  if (s.area_plugins.size() != areas_.size())
    refuse("it has " + std::to_string(s.area_plugins.size()) + " areas, this world " +
           std::to_string(areas_.size()));
  const std::size_t slots = s.objects.generations.size();
  if (s.area_of_slot.size() > slots) refuse("it gives areas to slots that do not exist");
  for (int a : s.area_of_slot)
    if (a < -1 || a >= int(areas_.size()))
      refuse("it puts an object in area " + std::to_string(a) + ", which does not exist");
  for (ObjectId id : s.frozen)
    if (id.index >= slots || !s.objects.alive[id.index] ||
        s.objects.generations[id.index] != id.generation)
      refuse("a frozen object (#" + std::to_string(id.index) + ") is not alive in it");
  std::vector<const ColumnBase*> columns(properties().size(), nullptr);
  for (const Snapshot::Column& c : s.columns) {
    const auto id = properties().find(c.property);
    if (!id) refuse("it holds property '" + c.property + "', which this world does not know");
    const PropertyDef& def = properties().def(*id);
    if (def.kind != c.kind)
      refuse("property '" + c.property + "' is " + std::string(to_string(c.kind)) + " in it and " +
             std::string(to_string(def.kind)) + " in this world");
    if (!c.values || c.values->presence().size() != slots)
      refuse("its column '" + c.property + "' does not cover its " + std::to_string(slots) +
             " slots");
    columns[*id] = c.values.get();
  }
  std::vector<ScheduledInput> inputs;
  for (const Snapshot::Input& in : s.inputs) {
    const auto id = properties().find(in.property);
    if (!id)
      refuse("a pending input sets property '" + in.property + "', which this world does not know");
    inputs.push_back(ScheduledInput{in.time, in.id, *id, in.value});
  }
  for (const auto* list : {&s.disabled, &s.enabled})
    for (const auto& name : *list)
      if (!plugins_.find(name)) refuse("it names plugin '" + name + "', which is not registered");
  for (const auto& a : s.area_plugins)
    for (const auto& name : a)
      if (!plugins_.find(name))
        refuse("an area uses plugin '" + name + "', which is not registered");

  // Owners of outside state (the mods) read and check theirs, and run their
  // migrations, while everything can still be refused.
  std::vector<std::function<void()>> commits;
  for (const StateOwner& o : state_owners_)
    if (o.prepare)
      if (auto c = o.prepare(s)) commits.push_back(std::move(c));

  // The store checks its object table before it changes anything.
  store_.restore(s.objects, columns);
  for (auto& c : commits) c();
  slots_.clear();
  resolvers_.clear();
  derived_.clear();
  interactions_.clear();
  outside_.clear();
  step_ = s.step;
  time_ = s.time;
  def_.dt = s.dt;
  inputs_ = std::move(inputs);
  next_input_ = 0;
  swaps_.clear();
  for (const Snapshot::Swap& sw : s.swaps)
    swaps_.push_back(ScheduledSwap{sw.time, sw.area, sw.from, sw.to});
  disabled_ = s.disabled;
  enabled_ = s.enabled;
  def_.use.clear();
  for (const auto& [what, plugin] : s.use) def_.use.emplace(what, plugin);
  for (std::size_t i = 0; i < areas_.size(); ++i) {
    areas_[i].def.plugins = s.area_plugins[i];
    areas_[i].left.clear();
  }
  frozen_ = s.frozen;
  frozen_changed_ = true;
  area_of_slot_ = s.area_of_slot;
  // Which position-less objects are split follows from the areas above and
  // the references restored: recomputed, not saved (the format is unchanged).
  split_.assign(area_of_slot_.size(), {});
  if (const Column<Vec3>* position = position_column()) {
    const std::vector<RefColumn> refs = ref_columns();
    std::vector<int> found;
    for (std::uint32_t slot = 0; slot < area_of_slot_.size(); ++slot)
      if (store_.id_at(slot) && !position->has(slot)) {
        referent_areas(slot, position, refs, found);
        if (found.size() > 1) split_[slot] = found;
      }
  }
  refresh_live();
  refresh_area_scopes();
  pending_.clear();
  published_.clear();
  current_stage_ = nullptr;
  started_ = s.started;
  synced_ = false;
  primed_ = false;
  advanced_ = false;
  if (!started_) return;  // start() instantiates, builds and primes

  // Every stage afresh, built from the restored properties.
  sync_structure();
  if (active_stages() != s.stages) {
    std::string now, then;
    for (const auto& n : active_stages()) now += " " + n;
    for (const auto& n : s.stages) then += " " + n;
    throw InputError("restored the snapshot, but this world instantiates the stages" + now +
                     " where the snapshot had" + then);
  }
  // A build derives some properties again from the others (the rigid body
  // writes back each pose it normalised): the snapshot's bits are the truth,
  // put back before the stages take their own state from it.
  store_.reinstate(columns);
  for (const Snapshot::StageState& st : s.stage_states) {
    Slot* slot = find_slot(st.stage);
    if (!slot)
      throw InputError("restored the snapshot, but it holds the state of stage '" + st.stage +
                       "', which is not active");
    StateReader in(st.stage, st.bytes);
    slot->stage->restore_state(in);
    if (in.remaining() != 0)
      throw InputError("stage '" + st.stage + "' left " + std::to_string(in.remaining()) +
                       " bytes of its saved state unread: it is damaged or from another version");
  }
  // Prime as the end of the step that led to the snapshot did: derived sets
  // and interactions from the restored properties, in the same phase context
  // (the step counter of that step, its advance done), so that the next
  // advance performs the same commands. A snapshot of step 0 is primed as
  // start() primes.
  if (step_ == 0) {
    derive_phase();
    interact_phase();
  } else {
    --step_;
    primed_ = true;
    advanced_ = true;
    derive_phase();
    interact_phase();
    advanced_ = false;
    ++step_;
  }
  pending_.clear();  // their events were published before the snapshot
  for (auto& slot : slots_) slot->primed = true;
  primed_ = true;
  // The run that took the snapshot rebuilds every resolver at its next step:
  // so does this one (the rebuild is not neutral: it measures from properties).
  if (s.resync) synced_ = false;
}

}  // namespace alloy
