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

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "runtime/access.hpp"
#include "runtime/events.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/profile.hpp"

namespace alloy {

class World;

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
};

/// What every stage may see: properties read-only, derived sets, events.
class WorldView {
 public:
  explicit WorldView(const World& w) : world_(w) {}
  const PropertyRegistry& properties() const;
  const PropertyStore& store() const;
  PropertyId property(std::string_view name) const;
  template <class T> ColumnView<T> column(PropertyId id) const;
  template <class T> ColumnView<T> column(std::string_view name) const {
    return column<T>(property(name));
  }
  std::uint64_t step() const;
  double time() const;
  double dt() const;
  /// Records an event for this step's publish phase.
  void emit(Event e) const;

 protected:
  const World& world_;
};

/// What a resolver gets in build() and advance(): everything a view gives,
/// plus writers for the columns it declared, and nothing else.
class ResolverAccess : public WorldView {
 public:
  ResolverAccess(World& w, const std::string& stage, const std::vector<PropertyId>& writes)
      : WorldView(w), mutable_world_(w), stage_(stage), writes_(writes) {}
  /// Throws AccessError if the resolver did not declare `id` in its writes.
  template <class T> ColumnWriter<T> writer(PropertyId id);
  template <class T> ColumnWriter<T> writer(std::string_view name) {
    return writer<T>(property(name));
  }

 private:
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
  /// Input scheduled ahead, such as a scene's timeline ("at t = 1 s the switch
  /// bar is let go"): the edit is applied like a player's hand, between steps,
  /// at the start of the first step that begins at or after `time`, and is
  /// published as an "input" event. The value is checked now (InputError).
  void schedule(double time, ObjectId id, PropertyId property, const PropertyValue& value);
  /// Scheduled edits not yet applied.
  std::size_t pending_inputs() const { return inputs_.size() - next_input_; }
  ObjectId find(std::string_view name) const { return store_.find(name); }
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
  WorldView view() const { return WorldView(*this); }

  // --- stages -----------------------------------------------------------------
  bool has_stage(std::string_view name) const;
  Stage* stage(std::string_view name);
  /// Active stage names in run order.
  std::vector<std::string> active_stages() const;

  PluginRegistry& plugins() { return plugins_; }
  PropertyStore& store() { return store_; }
  const PropertyStore& store() const { return store_; }
  const PropertyRegistry& properties() const { return plugins_.properties(); }

 private:
  friend class WorldView;
  friend class ResolverAccess;
  friend class PluginContext;
  struct Slot;

  struct ScheduledInput {
    double time;
    ObjectId id;
    PropertyId property;
    PropertyValue value;
  };
  void apply_inputs();
  void advance_phase();
  void derive_phase();
  void interact_phase();
  void publish_phase();
  void sync_structure();
  void prime_new_stages();
  void activate_needed();
  bool needed(const PluginDef& def) const;
  void instantiate(const PluginDef& def);
  void order_stages();
  bool due(const Slot& s) const;
  bool inputs_changed(Slot& s) const;


  PluginRegistry& plugins_;
  WorldDef def_;
  PropertyStore store_;
  std::vector<std::unique_ptr<Slot>> slots_;  // active stages
  std::vector<Slot*> resolvers_, derived_, interactions_;
  std::vector<ScheduledInput> inputs_;  // sorted by time, stable
  std::size_t next_input_ = 0;
  std::uint64_t step_ = 0;
  double time_ = 0;
  bool started_ = false;
  bool synced_ = false;
  bool primed_ = false;  // start() has primed the pipeline
  std::uint64_t seen_structure_ = 0;
  const std::string* current_stage_ = nullptr;  // for Event::source
  mutable std::vector<Event> pending_;
  std::vector<Event> published_;
  std::vector<Observer> observers_;
  Profile profile_;
};

// ---------------------------------------------------------------------------

template <class T>
ColumnView<T> WorldView::column(PropertyId id) const {
  return ColumnView<T>(&world_.store_.typed<T>(id), &world_.store_);
}

template <class T>
ColumnWriter<T> ResolverAccess::writer(PropertyId id) {
  for (PropertyId w : writes_)
    if (w == id) return ColumnWriter<T>(&mutable_world_.store_.typed_mut<T>(id));
  throw AccessError("resolver '" + stage_ + "' may not write '" + properties().def(id).name +
                    "': it is not in the resolver's declared writes");
}

}  // namespace alloy
