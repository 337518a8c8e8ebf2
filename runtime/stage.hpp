// The three kinds of stage of the method (paper section 3) and their contracts.
//
//   Resolver     one kind of physics. The only stage that changes properties,
//                and only the columns it declared in `writes`. Performs in its
//                advance() the commands that interactions queued in the previous
//                interact phase (the one-step delay of paper 3.2).
//   DerivedSet   a pure function of properties and published resolver state
//                (contacts, magnetic forces). Reads everything, writes only its
//                own members. Skipped when none of its inputs changed.
//   Interaction  reads properties and derived sets, and queues commands on
//                exactly one resolver (its `target`). Never writes a property.
//
// All stages run on the world's thread, in a fixed order, one phase at a time:
// nothing else runs while a stage runs, and no stage sees another's half-done
// work. A stage must not call into the world's editing API.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "runtime/energy_ledger.hpp"
#include "runtime/error.hpp"
#include "runtime/property_types.hpp"
#include "runtime/stage_state.hpp"

namespace alloy {

class WorldView;
class ResolverAccess;

enum class StageKind : std::uint8_t { Resolver, Derived, Interaction };
std::string_view to_string(StageKind kind);

/// What a stage declares about itself. The world uses it to decide whether the
/// stage is needed, in which order stages run, which columns a resolver may
/// write, and when a derived set may be skipped.
struct StageInfo {
  std::string name;  ///< plugin name, e.g. "rigid_body", "gravity.uniform"
  StageKind kind = StageKind::Resolver;
  std::vector<std::string> reads;   ///< property columns read
  std::vector<std::string> writes;  ///< property columns written (resolvers only)
  /// The stage is instantiated only if some object carries at least one of
  /// these properties. Empty: needed whenever its dependencies are.
  std::vector<std::string> needs;
  std::vector<std::string> derived;    ///< derived sets read (DPS and interactions)
  std::vector<std::string> resolvers;  ///< resolvers whose published state is read (DPS)
  std::string target;                  ///< interactions: the one resolver they queue on
  /// What the stage provides, when several plugins are alternatives for it
  /// ("gravity": gravity.uniform or gravity.nbody). In any one scope only one
  /// provider of a thing is active: the scene's choice, else the first registered.
  std::string provides;
  /// Dependencies (target, derived, resolvers) that must be these very
  /// plugins, not another provider of the same thing: a stage written against
  /// one engine's internals (ODE's collision set and contact queue) names that
  /// engine here, and is not instantiated where another engine provides it.
  /// A dependency not listed is met by the plugin of that name or by any
  /// plugin that provides it (`rigid_body`: ODE's or rigid_body.box2d).
  std::vector<std::string> exact;
  std::string doc;  ///< one line for `alloy plugins` and docs
  /// Who defined the stage: the mod's name for a Lua stage, "" for a native
  /// plugin. Messages that blame a stage name its mod too (a mod chooses its
  /// stages' names, so the name alone does not say whose they are).
  std::string owner;
};

/// Settings given to a plugin by a scene (e.g. `gravity.uniform { g = {0,-9.81,0} }`).
class PluginSettings {
 public:
  void set(std::string key, PropertyValue v) { values_[std::move(key)] = std::move(v); }
  bool has(std::string_view key) const { return values_.find(key) != values_.end(); }
  double number(std::string_view key, double fallback) const;
  std::int64_t integer(std::string_view key, std::int64_t fallback) const;
  bool boolean(std::string_view key, bool fallback) const;
  Vec3 vec3(std::string_view key, Vec3 fallback) const;
  std::string string(std::string_view key, std::string fallback) const;
  /// Throws InputError naming the first key not in `known`.
  void check_known(std::string_view plugin, const std::vector<std::string>& known) const;
  const std::map<std::string, PropertyValue, std::less<>>& values() const { return values_; }
  ErrorLocation where;  ///< where the settings were written, for messages

 private:
  std::map<std::string, PropertyValue, std::less<>> values_;
};

class Stage {
 public:
  virtual ~Stage() = default;
  /// Called after the set of objects or their memberships changed (objects
  /// created, destroyed, properties added or removed) and before the next phase.
  virtual void on_structure_changed(const WorldView&) {}

  // --- state outside properties (snapshots, saves, state hashes) -------------
  // A stage whose next step depends on something it keeps itself (a solver's
  // warm start, a coil's current, a voice in flight, a random generator)
  // saves it here; a stage whose state is all in properties, or that rebuilds
  // it bit for bit from them, declares nothing (the defaults).
  //
  // The contract (World::snapshot, World::restore): between steps, the world
  // calls save_state() on every active stage. On restore it creates every
  // stage afresh, builds each resolver from the restored properties
  // (Resolver::build), then calls restore_state() with exactly the bytes
  // that instance saved, then primes derived sets and interactions from the
  // restored properties as it does at the end of a step. From there, stepping
  // must give the same bits, in every property and in every later
  // save_state(), as the run that was never interrupted. restore_state()
  // must read every byte it is given (the world checks), and throws
  // InputError (StateReader does) on bytes it cannot read.

  /// Writes the stage's state to `out`; returns false if it has none (then
  /// nothing it wrote is kept and restore_state is not called).
  virtual bool save_state(StateWriter& /*out*/) const { return false; }
  /// Reads back what save_state wrote, after build(). Called only for a stage
  /// that saved something.
  virtual void restore_state(StateReader& /*in*/) {}

  // --- energy (runtime/energy_ledger.hpp, docs/energy.md) ----------------------
  /// Reports the energy the stage moved since its last report (sources,
  /// sinks, transfers; then starts its sums again from 0) and the energy it
  /// holds now (stores). Called between steps by EnergyLedger::record, only
  /// when a ledger is kept; a stage that moves no energy reports nothing
  /// (the default). Must not change anything the next step depends on.
  /// `view` is the stage's own (scoped to its area).
  virtual void report_energy(const WorldView& /*view*/, EnergyReport& /*out*/) {}
};

class Resolver : public Stage {
 public:
  /// Objects in `left` have just left this resolver's area (they keep every
  /// property; another area's resolvers take them over). Called before the
  /// rebuild that follows; a resolver may erase values it published for them.
  virtual void on_scope_exit(ResolverAccess&, std::span<const std::uint32_t> left) {}
  /// Builds internal state from properties alone: after creation, after a
  /// swap, after a structural change. A resolver whose state matters keeps it
  /// in properties, so that a rebuild loses nothing.
  virtual void build(ResolverAccess& access) = 0;
  /// Performs the queued commands, then integrates over `dt` (the world's step
  /// times `every`). Writes only through `access`.
  virtual void advance(ResolverAccess& access, double dt) = 0;
  /// Moves whenever state published to derived sets changes (0: none published).
  virtual std::uint64_t state_version() const { return 0; }
};

class DerivedSet : public Stage {
 public:
  /// Recomputes the derived data. Called only when an input changed.
  virtual void update(const WorldView& world) = 0;
  /// True if only the stages that list it among their inputs read its data
  /// and it publishes no event a step must not miss. It is then recomputed
  /// only in the steps where one of those readers runs: read by an
  /// interaction whose target runs every n-th step, once in n steps, from
  /// the state just before that advance. A tool that reads it between steps
  /// (the viewer) may see it as of the last step that did.
  virtual bool on_demand() const { return false; }
};

class Interaction : public Stage {
 public:
  /// Reads, and queues commands on the target resolver bound at creation.
  virtual void apply(const WorldView& world) = 0;
};

}  // namespace alloy
