// The world: objects and properties, the active stages, and the step.
//
//   World::step()
//     1 advance   each resolver performs its queued commands, then integrates
//     2 derive    each derived set recomputes, if one of its inputs changed
//     3 interact  each interaction reads and queues commands on its one target
//     4 publish   the step's events go to observers
//
// Edits from outside (scene loading, the viewer, a test) go through the
// editing API between steps. They are the world's input, like a player's hand:
// they change properties directly, and resolvers pick the change up from the
// columns' change counters or from on_structure_changed / build.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "runtime/access.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/events.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/profile.hpp"
#include "runtime/snapshot.hpp"
#include "runtime/state_owner.hpp"

namespace alloy {

class World;

/// A named region of the world with its own set of plugins (paper section 3:
/// uniform gravity on a planet, N-body gravity in orbit). An object is in the
/// first area, in the order given, whose region holds its position; it keeps
/// every property when it crosses a border, only the stages acting on it change.
struct AreaDef {
  std::string name;
  /// The region: a sphere if radius > 0, else a box of these half extents
  /// about the centre; with neither, everywhere (a catch-all, put it last).
  Vec3 center;
  Vec3 half_extents;
  double radius = 0;
  /// Plugins instanced in this area, acting only on its objects. A plugin
  /// that provides something (StageInfo::provides) replaces the global
  /// provider of it for the objects in the area.
  std::vector<std::string> plugins;
  std::map<std::string, PluginSettings, std::less<>> settings;

  bool contains(Vec3 p) const;
};

/// An edit made to the world from outside, between steps, as the world
/// tells its input observers (World::add_input_observer) once it has been
/// made: the one place a recorder (runtime/replay.hpp) learns every input,
/// whoever made it (the viewer's tools, its undo, a test, a script).
/// Edits the world makes itself are not told: timeline inputs and scheduled
/// swaps when they come due (a snapshot holds them; their scheduling from
/// outside is told), and an edit made inside another (the restore inside
/// sync(), the swaps of a scene's timeline).
struct WorldInput {
  enum class Kind : std::uint8_t {
    Set,             ///< id, property, value (World::set)
    Remove,          ///< id, property (World::remove)
    Create,          ///< id (the one made), name (World::create)
    Destroy,         ///< id (World::destroy)
    Unfreeze,        ///< id (World::unfreeze)
    Swap,            ///< area, from, to (World::swap)
    PluginChanged,   ///< name: the plugin (World::plugin_changed)
    Restore,         ///< snapshot (World::restore)
    Sync,            ///< nothing (World::sync)
    Stepped,         ///< not an input: a step() has ended (for per-step hashes)
    Schedule,        ///< time, id, property, value (World::schedule, as checked)
    ScheduleSwap,    ///< time, area, from, to (World::schedule_swap)
    DemandImpulses,  ///< value: true (held) or false (released) (World::demand_impulses)
  };
  Kind kind = Kind::Set;
  ObjectId id;                         ///< Set, Remove, Create, Destroy, Unfreeze
  std::string property;                ///< Set, Remove
  PropertyValue value;                 ///< Set, Schedule (as the store keeps it); DemandImpulses
  double time = 0;                     ///< Schedule, ScheduleSwap: when it comes due, s
  std::string name;                    ///< Create: the object's name; PluginChanged: the plugin
  std::string area, from, to;          ///< Swap
  const Snapshot* snapshot = nullptr;  ///< Restore: valid during the call only
};

/// Definition of a world, with defaults (Box2D's b2DefaultWorldDef idea).
struct WorldDef {
  double dt = 1.0 / 240.0;  ///< fixed step, s
  /// Plugins this world may instantiate, by name; empty means every plugin in
  /// the registry. Each is still instantiated only if the scene needs it.
  std::vector<std::string> plugins;
  /// Per-plugin settings, by plugin name.
  std::map<std::string, PluginSettings, std::less<>> settings;
  /// Run a stage only every n-th step (a resolver then advances by n * dt).
  std::map<std::string, int, std::less<>> every;
  /// Which plugin provides a thing globally, e.g. {"gravity", "gravity.nbody"};
  /// otherwise the first registered provider.
  std::map<std::string, std::string, std::less<>> use;
  std::vector<AreaDef> areas;
};

/// What every stage may see: properties read-only, derived sets, events.
class WorldView {
 public:
  explicit WorldView(const World& w, const Scope* scope = nullptr) : world_(w), scope_(scope) {}
  /// The objects this stage acts on (its area), or null for every object.
  const Scope* scope() const { return scope_; }
  const PropertyRegistry& properties() const;
  const PropertyStore& store() const;
  PropertyId property(std::string_view name) const;
  template <class T>
  ColumnView<T> column(PropertyId id) const;
  template <class T>
  ColumnView<T> column(std::string_view name) const {
    return column<T>(property(name));
  }
  std::uint64_t step() const;
  double time() const;
  double dt() const;
  /// The `every` the world's definition gives the stage or plugin `name` (1
  /// if none): a stage that feeds a resolver run every n-th step knows how
  /// long the advance its commands act over is (n * dt()).
  int every(std::string_view name) const;
  /// Records an event for this step's publish phase.
  void emit(Event e) const;

 protected:
  const World& world_;
  const Scope* scope_ = nullptr;
};

/// What a resolver gets in build() and advance(): everything a view gives,
/// plus writers for the columns it declared, and nothing else.
class ResolverAccess : public WorldView {
 public:
  ResolverAccess(World& w, const std::string& stage, const std::vector<PropertyId>& writes,
                 const Scope* scope = nullptr)
      : WorldView(w, scope), mutable_world_(w), stage_(stage), writes_(writes) {}
  /// Throws AccessError if the resolver did not declare `id` in its writes.
  template <class T>
  ColumnWriter<T> writer(PropertyId id);
  template <class T>
  ColumnWriter<T> writer(std::string_view name) {
    return writer<T>(property(name));
  }
  /// Refuses a value that is finite but would break the resolver (a load that
  /// would fling a body past its speed limit, a pose beyond the world's
  /// extent) and freezes the object in `slot`, as a non-finite write does
  /// (World::frozen). Publishes an "out_of_bounds" event: source: `source`
  /// (the stage that gave the value; empty: this resolver), a: the object,
  /// text: what was refused and why, values: its numbers. Once per freeze.
  void refuse(std::uint32_t slot, const std::string& source, std::string text,
              std::vector<std::pair<std::string, double>> values = {});

 private:
  friend void detail::non_finite_write(ResolverAccess*, std::uint32_t, PropertyId, const double*,
                                       int);
  friend void detail::out_of_scope_write(ResolverAccess*, std::uint32_t);
  World& mutable_world_;
  const std::string& stage_;
  const std::vector<PropertyId>& writes_;
};

class World {
 public:
  World(PluginRegistry& plugins, WorldDef def = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // --- editing (between steps) ----------------------------------------------
  ObjectId create(const std::string& name = "");
  void destroy(ObjectId id);
  /// Sets a property by name; type-checked; InputError on unknown names or bad types.
  void set(ObjectId id, std::string_view property, const PropertyValue& value);
  void set(ObjectId id, PropertyId property, const PropertyValue& value);
  void remove(ObjectId id, std::string_view property);
  PropertyValue get(ObjectId id, std::string_view property) const;
  /// The value if `property` is registered, the object carries it and it is a
  /// T (a number may be read from an integer property); else nullopt. For
  /// tools and checks, not for a stage's inner loop.
  template <class T>
  std::optional<T> value(ObjectId id, std::string_view property) const;
  /// Input scheduled ahead, such as a scene's timeline ("at t = 1 s the switch
  /// bar is let go"): the edit is applied like a player's hand, between steps,
  /// at the start of the first step that begins at or after `time`, and is
  /// published as an "input" event. The value is checked now (InputError).
  void schedule(double time, ObjectId id, PropertyId property, const PropertyValue& value);
  /// Scheduled edits not yet applied.
  /// (A call from outside, between steps, is an input: told to the input
  /// observers, so that a recording made after the scene loaded replays it.)
  std::size_t pending_inputs() const { return inputs_.size() - next_input_; }
  ObjectId find(std::string_view name) const { return store_.find(name); }
  /// Runs every registered plugin's whole-object check on `id`; throws
  /// InputError naming the object.
  void check(ObjectId id) const;
  std::string describe(ObjectId id) const { return store_.describe(id); }

  // --- running --------------------------------------------------------------
  /// Instantiates the needed stages, builds resolvers from properties, and
  /// primes derived sets and interactions so that the first advance has its
  /// commands. Called by the first step() if not called before.
  void start();
  void step();
  void run(std::uint64_t steps) {
    for (std::uint64_t i = 0; i < steps; ++i) step();
  }

  /// Changes the fixed step; only before the world starts (no variable dt).
  void set_dt(double dt);

  std::uint64_t step_count() const { return step_; }
  double time() const { return time_; }
  double dt() const { return def_.dt; }
  const WorldDef& def() const { return def_; }

  // --- observing --------------------------------------------------------------
  /// Events of the last step, in order.
  const std::vector<Event>& events() const { return published_; }
  using Observer = std::function<void(const Event&)>;
  void add_observer(Observer observer) { observers_.push_back(std::move(observer)); }
  const Profile& profile() const { return profile_; }
  /// Whether steps read the clock for the profile's seconds (per stage and
  /// per phase). Off by default: a scene pays nothing for a profile nobody
  /// reads (16 clock reads a step were 0.8 % of the Box2D pile's time). The
  /// counts (steps, runs, skipped) are kept either way. `alloy run
  /// --profile`, the viewer's stage panel and the benchmarks turn it on.
  void set_timing(bool on) { timing_ = on; }
  bool timing() const { return timing_; }
  WorldView view() const { return WorldView(*this); }
  /// Every edit from outside (WorldInput), after it is made, and the end of
  /// every step. An edit that throws is not told. Observers cannot be
  /// removed: one that outlives its owner holds it weakly (Recorder does).
  using InputObserver = std::function<void(const WorldInput&)>;
  void add_input_observer(InputObserver observer) {
    input_observers_.push_back(std::move(observer));
  }
  /// While one is alive, the world's edits are parts of one larger input that
  /// its maker tells in its own way, and are not told one by one: a mod's
  /// reload (lua::ModRuntime), which a recording logs from its "mod_reloaded"
  /// event and a replay makes again by reloading the mod.
  class QuietInputs {
   public:
    explicit QuietInputs(World& w) : world_(w) { ++world_.input_depth_; }
    ~QuietInputs() { --world_.input_depth_; }
    QuietInputs(const QuietInputs&) = delete;
    QuietInputs& operator=(const QuietInputs&) = delete;

   private:
    World& world_;
  };

  // --- impulses demanded from outside ------------------------------------------
  /// An edit: while `on`, from the next step on, every contact set of the
  /// world computes impulses, as if one of its readers demanded them
  /// (ContactSet::demand_impulses). For a viewer that draws contact forces:
  /// the demand changes what the contact sets and the rigid body keep and
  /// save (impulse totals, whether impulses are known), so it is an input,
  /// told to the input observers and made again by a replay. Not in a
  /// snapshot: a restore keeps the world's own setting. Setting the value it
  /// has does nothing and is not told.
  void demand_impulses(bool on);
  bool impulses_demanded() const { return impulses_demanded_; }

  // --- energy books ---------------------------------------------------------------
  /// Whether an energy ledger has asked the stages for their books
  /// (EnergyLedger::record): a stage made later in the run (an engine swapped
  /// in) keeps them from its first advance, not from its first report, so
  /// that the step it was made in is booked too. Changes no state.
  void keep_energy_books() { energy_books_ = true; }
  bool energy_books_kept() const { return energy_books_; }

  // --- frozen objects ------------------------------------------------------------
  // A resolver that writes a non-finite value (NaN, +-Inf) into a property is
  // refused (the old value stays), a "non_finite" event is published (source:
  // the resolver's stage, a: the object, text: the property's name, values:
  // the refused numbers), and the object is frozen: from the next structure
  // sync (the start of the next step) it is in no stage's scope, as if it had
  // left every area, so that each resolver rebuilds without it and the NaN
  // cannot spread (the rigid body drops its ODE body). It keeps every
  // property, with its last finite values.
  bool frozen(ObjectId id) const;
  /// Frozen objects, by slot.
  std::vector<ObjectId> frozen_objects() const { return frozen_; }
  /// An edit: the object rejoins every stage that wants it at the next step
  /// (fix its properties first, or it may be frozen again).
  void unfreeze(ObjectId id);
  /// The stage running now (an interaction queueing a command, a resolver
  /// advancing), or null between phases. A resolver reads it when a command is
  /// queued, to name the stage that gave a value it refuses later.
  const std::string* running_stage() const { return current_stage_; }

  // --- areas and swaps ---------------------------------------------------------
  /// The area an object is in, or "" (none). Updated after each advance (where
  /// the resolvers left it) and at the start of each step (where edits put it).
  std::string area_of(ObjectId id) const;
  /// An object without a position (a joint, a spring, a wire) is scoped by
  /// the objects it refers to (its Ref and RefList properties) that have a
  /// position and are not frozen: in their area when they are all in one,
  /// in none when it refers to none. When they lie in different areas it is
  /// split: in no area, and in a global stage's scope only if that stage acts
  /// on all of them, so no stage that differs between those areas acts on it
  /// (a joint between bodies on two engines is suspended until they are on
  /// one again). Its referents' areas, ascending ("" for none), while split;
  /// empty otherwise. Events: "area_split" (a: the object, text: the areas)
  /// when it splits, "area_entered" ("(split) -> area") when it is whole again.
  std::vector<std::string> split_areas(ObjectId id) const;
  /// Replaces plugin `from` with `to` (another implementation of the same
  /// kind) in `area`, or globally when `area` is empty, between steps. The new
  /// stage builds its state from the properties, so nothing is lost; the
  /// stages that depended on the old one are recreated. Throws InputError.
  void swap(std::string_view area, std::string_view from, std::string_view to);
  /// The same at a time to come (a scene's timeline, `alloy run --swap`).
  /// An input, told as schedule() is.
  void schedule_swap(double time, std::string area, std::string from, std::string to);
  /// The registry's definition of `plugin` changed or is gone (a mod was
  /// reloaded or unloaded), between steps: every stage of it, globally and in
  /// areas, is removed with the stages that depend on it, and whatever the
  /// registry still holds and the objects still need is instantiated again,
  /// built from properties and primed (at once if the world has started, else
  /// at start). Properties stay. Returns the stage instances removed.
  std::vector<std::string> plugin_changed(std::string_view plugin);

  // --- snapshots (snapshot.hpp, docs/saves.md) ---------------------------------
  /// Everything that decides the next step, as a value; between steps. With a
  /// `base` taken from this world, every column that has not changed since
  /// is shared with the base instead of copied (a delta snapshot).
  Snapshot snapshot(const Snapshot* base = nullptr) const;
  /// Puts the world back in the state of `snapshot`, taken from this world or
  /// from another built from the same scene (the same plugins, properties and
  /// areas): ids held before stay valid as the snapshot knew them. Every stage
  /// is created afresh, built from the restored properties, given its saved
  /// state (Stage::restore_state) and primed as at the end of a step; events
  /// already published are dropped. From there, stepping gives the bits the
  /// run that took the snapshot gave, for every stage that keeps its state in
  /// properties or saves it (docs/saves.md lists the ones that do not yet).
  /// Throws InputError, before changing anything, on a snapshot that does not
  /// fit this world (an unknown property or one of another kind, other areas,
  /// a damaged object table); and, after, if the stages it names are not the
  /// ones the restored world instantiates or one refuses its state.
  void restore(const Snapshot& snapshot);
  /// Brings the stage set up to date after edits between steps (objects
  /// created or destroyed, memberships changed, a swap, a freeze): the stages
  /// the objects now need are instantiated, every stage is built afresh from
  /// the properties and given its own state back, as restore() does. Changes
  /// no property bit. Afterwards snapshot() comes back bit for bit (restoring
  /// it gives the same later steps as going on), which it does not always do
  /// right after an edit: the next step() would rebuild the resolvers in
  /// place, and a rebuild in place is not neutral (a rigid body grown part by
  /// part steps a few bits apart from one built at once). Does nothing before
  /// the world has started. The viewer calls it after each edit it records.
  void sync();
  /// What each active stage saves of itself (Stage::save_state), in run order.
  std::vector<Snapshot::StageState> stage_states() const;
  /// State outside the world that its snapshots carry (state_owner.hpp): the
  /// mods' state tables. Owners are asked in the order they were added.
  void add_state_owner(StateOwner owner) { state_owners_.push_back(std::move(owner)); }
  /// Called after each stage that ran in a step (advance, derive, interact),
  /// with its instance name: replays hash the world there to name the stage
  /// after which a run first differs (runtime/replay.hpp). One hook; an empty
  /// function removes it.
  using StageHook = std::function<void(const std::string& stage)>;
  void set_stage_hook(StageHook hook) { stage_hook_ = std::move(hook); }

  // --- stages -----------------------------------------------------------------
  /// Stages are named after their plugin, with "@area" for a stage of an area
  /// ("gravity.nbody@orbit").
  bool has_stage(std::string_view name) const;
  Stage* stage(std::string_view name);
  /// The stage that a stage declared by `of`, in `area` ("": global), gets
  /// for its dependency `name`: the area's own, else the global one, of the
  /// plugin so named or of one that provides `name` (StageInfo::exact).
  /// `instance`, if given, receives the found stage's instance name
  /// ("rigid_body.box2d@table").
  Stage* dependency_stage(const StageInfo& of, std::string_view area, std::string_view name,
                          std::string* instance = nullptr);
  /// Active stage names in run order.
  std::vector<std::string> active_stages() const;
  /// A view of the world as stage `name` sees it (scoped to its area; every
  /// object if there is no such stage), between steps: for tools that ask a
  /// stage about the world (EnergyLedger::record).
  WorldView stage_view(std::string_view name) const;

  PluginRegistry& plugins() { return plugins_; }
  /// The definition a stage instance ("name", or "name@area") was made
  /// from, or nullptr if no plugin of that name is registered now.
  const PluginDef* plugin_def(std::string_view stage) const {
    return plugins_.find(stage.substr(0, stage.find('@')));
  }
  PropertyStore& store() { return store_; }
  const PropertyStore& store() const { return store_; }
  const PropertyRegistry& properties() const { return plugins_.properties(); }

 private:
  friend class WorldView;
  friend class ResolverAccess;
  friend void detail::non_finite_write(ResolverAccess*, std::uint32_t, PropertyId, const double*,
                                       int);
  friend void detail::out_of_scope_write(ResolverAccess*, std::uint32_t);
  friend class PluginContext;
  /// Adds the object in `slot` to frozen_; its id, or null if it is dead or
  /// frozen already (one event per freeze).
  ObjectId freeze_slot(std::uint32_t slot);
  struct Slot;

  struct ScheduledInput {
    double time;
    ObjectId id;
    PropertyId property;
    PropertyValue value;
  };
  struct ScheduledSwap {
    double time;
    std::string area, from, to;
  };
  struct Area {
    AreaDef def;
    Scope scope;
    std::vector<std::uint32_t> left;  // slots that left at the last assignment
  };
  void apply_inputs();
  // The edits themselves, without telling the input observers.
  void swap_now(std::string_view area, std::string_view from, std::string_view to);
  std::vector<std::string> plugin_changed_now(std::string_view plugin);
  void sync_now();
  void restore_now(const Snapshot& s);
  struct Outside {
    std::vector<int> areas;  // excluded
    Scope scope;
  };
  bool assign_areas();
  /// Puts the object in `slot` in area `in` (-1: none), noting the slot in
  /// the area it left; tells an "area_entered" event if `tell`. Returns
  /// whether it moved.
  bool place(std::uint32_t slot, int in, bool tell);
  /// A Ref or RefList column with members (list: a RefList).
  struct RefColumn {
    const ColumnBase* column;
    bool list;
  };
  std::vector<RefColumn> ref_columns() const;
  /// The areas (ascending, -1: none) of the positioned, unfrozen objects
  /// that the position-less object in `slot` refers to through `refs`, into `out`.
  void referent_areas(std::uint32_t slot, const Column<Vec3>* position,
                      const std::vector<RefColumn>& refs, std::vector<int>& out) const;
  /// The second pass of assign_areas: every object without a position takes
  /// the area of its referents (split_ when they are in several). Returns
  /// whether an area or a split changed.
  bool assign_by_references(const Column<Vec3>* position);
  /// The position column, or null while no object has had a position.
  const Column<Vec3>* position_column() const;
  void refresh_area_scopes();
  void refresh_live();
  void rescope();
  bool frozen_slot(std::uint32_t slot) const;
  void refresh_outside(Outside& o) const;
  static bool listed_area(const std::vector<int>& v, int a) {
    return std::find(v.begin(), v.end(), a) != v.end();
  }
  static bool listed_slot(const std::vector<Slot*>& v, const Slot* s) {
    return std::find(v.begin(), v.end(), s) != v.end();
  }
  bool chosen_globally(const PluginDef& def) const;
  const Scope* global_scope(const PluginDef& def);
  bool needed_in(const PluginDef& def, int area) const;
  /// Whether a global interaction the area does not list acts there all the
  /// same, on the area's own provider of its target (the area replaces the
  /// engine, not the forces on its bodies).
  bool follows_area_provider(const PluginDef& def, int area) const;
  Slot* find_slot(std::string_view instance) const;
  Slot* dependency(const Slot& of, std::string_view plugin) const;
  void remove_with_dependents(Slot* s);
  void advance_phase();
  void derive_phase();
  void interact_phase();
  void publish_phase();
  void sync_structure();
  void prime_new_stages();
  void activate_needed();
  void instantiate(const PluginDef& def, int area);
  void order_stages();
  /// A "held_stage" event, once per pair, for each stage that reads the
  /// output of a derived set run less often than itself, and each interaction
  /// run less often than the resolver it commands (`every`): what the reader
  /// or the target gets in between is held, not recomputed.
  void report_held_stages();
  std::set<std::string> held_reported_;
  bool due(const Slot& s) const;
  /// Whether interaction `s`'s commands would be performed by its target's
  /// advance at `advance_step` (always, for a target that runs every step).
  bool feeds(const Slot& s, std::uint64_t advance_step) const;
  /// Whether derived set `s` is to be recomputed this step: always, unless it
  /// is on demand (DerivedSet::on_demand) and none of its readers runs.
  bool wanted(const Slot& s) const;
  bool inputs_changed(Slot& s) const;

  PluginRegistry& plugins_;
  WorldDef def_;
  PropertyStore store_;
  std::vector<std::unique_ptr<Slot>> slots_;  // active stages
  std::vector<Slot*> resolvers_, derived_, interactions_;
  std::vector<Area> areas_;
  std::vector<int> area_of_slot_;  // area index per object slot, -1 for none
  // Per slot: the areas (ascending, -1: none) of a split position-less
  // object's referents (split_areas()); empty for every other object.
  std::vector<std::vector<int>> split_;
  std::map<std::string, Outside, std::less<>>
      outside_;                        // scopes of global stages kept out of areas
  std::vector<std::string> disabled_;  // global plugins swapped out
  std::vector<std::string> enabled_;   // global plugins swapped in beyond def_.plugins
  std::vector<ScheduledSwap> swaps_;   // sorted by time
  // During a swap: the contact sets swapped out (area, what they provided,
  // the stage), kept alive until their replacements have taken their pairs.
  struct Retired {
    int area;
    std::string provides;
    std::unique_ptr<Stage> stage;
  };
  std::vector<Retired> retired_;
  std::vector<ScheduledInput> inputs_;          // sorted by time, stable
  bool impulses_demanded_ = false;              // demand_impulses()
  bool energy_books_ = false;                   // keep_energy_books()
  std::vector<ImpulseDemand> impulse_demands_;  // held for this step's advance
  std::size_t next_input_ = 0;
  std::uint64_t step_ = 0;
  double time_ = 0;
  bool started_ = false;
  bool synced_ = false;
  bool primed_ = false;    // start() has primed the pipeline
  bool advanced_ = false;  // within step(): this step's advance is done
  std::uint64_t seen_structure_ = 0;
  std::uint64_t seen_by_resolvers_ = 0;  // store_.resolver_membership_version() at the last sync
  std::vector<ObjectId> frozen_;         // by slot
  bool frozen_changed_ = false;          // since the last structure sync
  Scope live_;  // every object not frozen: the scope of global stages while any is frozen
  const std::string* current_stage_ = nullptr;  // for Event::source
  mutable std::vector<Event> pending_;
  std::vector<Event> published_;
  std::vector<Observer> observers_;
  std::vector<InputObserver> input_observers_;
  int input_depth_ = 0;  // edits under way: only the outermost is told
  /// Runs `edit` as one input: told to the input observers (made by
  /// `describe` after the edit) if it is the outermost and did not throw.
  template <class Edit, class Describe>
  auto as_input(Edit&& edit, Describe&& describe);
  void tell(const WorldInput& in) {
    for (const auto& o : input_observers_) o(in);
  }
  std::vector<StateOwner> state_owners_;
  StageHook stage_hook_;
  Profile profile_;
  bool timing_ = false;
  /// now_seconds() when timing, else 0 (every difference is then 0).
  double clock() const { return timing_ ? now_seconds() : 0.0; }
};

/// The narrated line of a "non_finite" event: "frozen: ball: rigid_body wrote
/// position = {nan, 0.5, 1}", or of an "out_of_bounds" event: "frozen: ball:
/// pusher queued add_force = {1e+12, 0, 0} N, ...".
std::string frozen_message(const World& world, const Event& e);

// ---------------------------------------------------------------------------

template <class T>
std::optional<T> World::value(ObjectId id, std::string_view property) const {
  const auto pid = properties().find(property);
  if (!pid || !store_.has(id, *pid)) return std::nullopt;
  const PropertyValue v = store_.get(id, *pid);
  if (const T* t = std::get_if<T>(&v)) return *t;
  if constexpr (std::is_same_v<T, double>)
    if (const auto* i = std::get_if<std::int64_t>(&v)) return double(*i);
  return std::nullopt;
}

template <class T>
ColumnView<T> WorldView::column(PropertyId id) const {
  return ColumnView<T>(&world_.store_.typed<T>(id), &world_.store_, scope_);
}

template <class T>
ColumnWriter<T> ResolverAccess::writer(PropertyId id) {
  for (PropertyId w : writes_)
    if (w == id) return ColumnWriter<T>(&mutable_world_.store_.typed_mut<T>(id), scope_, this);
  throw AccessError("resolver '" + stage_ + "' may not write '" + properties().def(id).name +
                    "': it is not in the resolver's declared writes");
}

}  // namespace alloy
