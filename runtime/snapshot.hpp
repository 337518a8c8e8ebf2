// A snapshot: everything that decides the world's next step, as a value
// (World::snapshot, World::restore; docs/saves.md).
//
// It holds every property column (with the kind the registry gave it), the
// object table (ids with their generations, the free list, names), the step,
// the time and the fixed step, the timeline's pending inputs and swaps, the
// stage set (which plugins are swapped in or out, globally and per area),
// each object's area, the frozen objects, and each stage's own state
// (Stage::save_state), and each mod's `state` table (mod_states, filled by
// the mods' runtime through World::add_state_owner). It does not hold the
// registry's definitions, the plugins' code or settings, the rest of the
// mods' Lua state (upvalues, globals), observers, events already published
// or profile timings: those come from the world it is restored into, which
// must be built from the same scene.
//
// Columns are immutable once taken and shared between copies of a snapshot,
// and between a delta snapshot and its base (World::snapshot(&base)): a
// column that did not change since the base is the base's column, not a copy.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "runtime/property_store.hpp"

namespace alloy {

struct Snapshot {
  /// One property column: a copy of the values and presence flags of every slot.
  struct Column {
    std::string property;                      ///< the property's name
    PropertyKind kind = PropertyKind::Number;  ///< its kind in the registry when taken
    std::shared_ptr<const ColumnBase> values;  ///< ColumnBase::clone()
    std::uint64_t version = 0;                 ///< the column's change counter when taken
    std::uint64_t membership_version = 0;      ///< its membership counter when taken
  };
  /// A timeline input not yet applied (World::schedule).
  struct Input {
    double time = 0;
    ObjectId id;
    std::string property;
    PropertyValue value;
  };
  /// A swap not yet made (World::schedule_swap).
  struct Swap {
    double time = 0;
    std::string area, from, to;
  };
  /// What a stage saved of itself (Stage::save_state).
  struct StageState {
    std::string stage;  ///< the instance: "plugin" or "plugin@area"
    std::vector<std::byte> bytes;
  };

  /// One mod's `state` table (docs/modding.md, "Mod state and migrations").
  ///
  /// For a save file: write `mod`, `version` and `bytes` as they are (two
  /// strings and a byte string); nothing in them refers to anything else in
  /// the snapshot but object slots, which the object table keeps valid.
  /// `bytes` is the state codec's output (lua/state_codec.hpp, format
  /// "alloy-mod-state-1"): a version byte, then the table as a tree of
  /// tagged values with keys in sorted order and numbers as their exact
  /// bits, so that equal states give equal bytes. Restore checks every byte
  /// (a damaged one is an InputError naming the mod), refuses a mod that is
  /// not loaded, and runs the mod's on_migrate(version, state) when `version`
  /// differs from the loaded mod's.
  struct ModState {
    std::string mod;               ///< the mod's name (its manifest's `name`)
    std::string version;           ///< its manifest's `version` when the snapshot was taken
    std::vector<std::byte> bytes;  ///< the state table, encoded
    friend bool operator==(const ModState&, const ModState&) = default;
  };

  std::uint64_t step = 0;  ///< World::step_count()
  double time = 0;         ///< World::time(), s
  double dt = 0;           ///< the fixed step, s
  bool started = false;    ///< taken after World::start() (stages built and primed)
  /// A structure sync (every resolver rebuilt) is due at the next step: the
  /// last step changed memberships (a resolver gave objects a column), or an
  /// object was frozen. The restored world resyncs then too.
  bool resync = false;
  PropertyStore::Objects objects;
  std::vector<Column> columns;    ///< every column the world had, by property name
  std::vector<ObjectId> frozen;   ///< World::frozen_objects()
  std::vector<int> area_of_slot;  ///< index of each slot's area, -1 for none
  std::vector<std::vector<std::string>> area_plugins;  ///< each area's plugins, after swaps
  std::vector<std::string> disabled;                   ///< global plugins swapped out
  std::vector<std::string> enabled;        ///< global plugins swapped in beyond the scene's list
  std::map<std::string, std::string> use;  ///< provider chosen for each thing, after swaps
  std::vector<std::string> stages;         ///< active stage instances, in run order
  std::vector<StageState> stage_states;    ///< the stages that saved something, in run order
  /// Every loaded mod with a runtime, in load order (empty in a world without
  /// mods). A world whose mods' runtime is not attached ignores them.
  std::vector<ModState> mod_states;
  std::vector<Input> inputs;  ///< pending, in the order they will be applied
  std::vector<Swap> swaps;    ///< pending, by time
  /// The store it was taken from (PropertyStore::lineage), for deltas.
  std::uint64_t lineage = 0;

  /// Bytes a snapshot takes, and how many of them it shares with `base`.
  struct Size {
    std::size_t bytes = 0;         ///< everything, shared columns included
    std::size_t shared_bytes = 0;  ///< in columns that are also `base`'s
    std::size_t columns = 0, shared_columns = 0;
    std::size_t own_bytes() const { return bytes - shared_bytes; }
  };
  Size size(const Snapshot* base = nullptr) const;
  /// The column of `property`, or null.
  const Column* column(std::string_view property) const;
};

}  // namespace alloy
