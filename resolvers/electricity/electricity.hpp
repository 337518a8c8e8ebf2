// The electricity resolver: DC circuits with coils, solved by modified nodal
// analysis (paper 3.2: "updates the electrical state of any given object,
// reacting to changes to the electrical circuit, such as new connections and
// broken connections"). docs/electricity.md has the model, the equations, the
// units and the limits.
//
// Parts   an object is an electrical part if it carries `emf` (battery),
//         `inductance` (coil), `capacitance` (capacitor), `switch_closed`
//         (switch), or `conductive` = true (with `resistance`: a resistor;
//         without: a single equipotential node such as a bar, a contact, the
//         striker). Batteries, coils, capacitors, switches and resistors have
//         two terminals, 0 and 1; a node part has one (terminal 1 means the
//         same node).
// Wires   objects carrying `wire_from` / `wire_to` (refs to parts) join two
//         terminals through `resistance`.
// Contacts made and broken by touching arrive as connect / disconnect
//         commands (from electricity_from_collisions) and are performed in the
//         next advance.
// Reads   conductive, emf, internal_resistance, inductance, resistance,
//         contact_resistance, wire_from, wire_to, wire_from_terminal,
//         wire_to_terminal, capacitance, switch_closed, current (the coil's
//         state), plate_charge (the capacitor's state).
// Writes  current, voltage, powered, on every part and wire; plate_charge on
//         capacitors.
// Time    coils and capacitors are integrated by the trapezoidal rule
//         (second order), with the first substep after any discontinuity (a
//         new network, an emf edit, an edited state) taken as two
//         backward-Euler half-steps, which damp the trapezoidal rule's
//         ringing (docs/electricity.md, "Coils and capacitors in time").
// Events  connected / disconnected (a, b) when a contact is made / broken;
//         circuit_closed / circuit_opened (a = battery, coil, capacitor,
//         switch or resistor, value "current"; a coil's circuit_opened also
//         "energy", the J its collapsing field released into the gap) when the
//         element joins / leaves a closed loop.
// Induction  set_induced_emf(coil, volts[, step_mean]), queued by
//         electricity_from_magnetism (resolvers/magnetism/): -dPhi/dt in series
//         with the coil, the value at the end of the next advance; the EMF
//         ramps linearly to it over the advance's substeps from the value in
//         force at the last substep, offset by a constant so that its mean
//         over the advance is step_mean when one is given (docs/electricity.md
//         "Induction", "The coupling's order").
// Rates   with the setting `rates = true` (the default), a coil also publishes
//         `current_rate`, dI/dt at the end of the advance (A/s), so that
//         magnetism_from_electricity can pass the current on with its rate
//         and the coil's magnet follows it between windows instead of a
//         window late (docs/performance.md "Multi-rate coupling").
//
// State that matters lives in properties: a coil's current is its `current`,
// a capacitor's charge its `plate_charge`, so build() loses nothing. Contacts are not stored: they
// are the touching pairs of the collisions set, and electricity_from_collisions re-sends every
// touching pair when it starts, so a new resolver instance recovers them.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "resolvers/electricity/mna.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy::electricity {

/// Property names: a contract with the Lua kit, the viewer and the other
/// resolvers (magnetism reads `current`). Keep them exactly.
namespace prop {
inline constexpr const char* kConductive = "conductive";
inline constexpr const char* kEmf = "emf";
inline constexpr const char* kInternalResistance = "internal_resistance";
inline constexpr const char* kInductance = "inductance";
inline constexpr const char* kResistance = "resistance";
inline constexpr const char* kContactResistance = "contact_resistance";
inline constexpr const char* kWireFrom = "wire_from";
inline constexpr const char* kWireTo = "wire_to";
inline constexpr const char* kWireFromTerminal = "wire_from_terminal";
inline constexpr const char* kWireToTerminal = "wire_to_terminal";
inline constexpr const char* kCurrent = "current";
inline constexpr const char* kVoltage = "voltage";
inline constexpr const char* kPowered = "powered";
inline constexpr const char* kCurrentRate = "current_rate";
inline constexpr const char* kCapacitance = "capacitance";
inline constexpr const char* kCharge = "plate_charge";
inline constexpr const char* kSwitchClosed = "switch_closed";
}  // namespace prop

/// Plugin names.
inline constexpr const char* kResolverName = "electricity";
inline constexpr const char* kFromCollisionsName = "electricity_from_collisions";
/// The induction coupling's order when a world does not set `induction_order`
/// (ElectricityConfig::induction_order; magnetism_from_electricity reads it too).
inline constexpr int kDefaultInductionOrder = 2;

/// Event types.
namespace event {
inline constexpr const char* kConnected = "connected";
inline constexpr const char* kDisconnected = "disconnected";
inline constexpr const char* kCircuitClosed = "circuit_closed";
inline constexpr const char* kCircuitOpened = "circuit_opened";
}  // namespace event

/// The property types electricity defines.
std::vector<PropertyDef> electricity_property_defs();

/// Smallest resistance the solver uses, Ohm: a value of 0 (an ideal wire or
/// battery) is taken as this, so that every element has a finite conductance
/// and a short circuit a huge but finite current.
inline constexpr double kMinResistance = 1e-6;

/// The ranges of the circuit values a scene may set (PropertyDef bounds:
/// refused at load and at every edit with the file, line and object;
/// docs/electricity.md "Values"). Each is far beyond a bench circuit, and
/// together they keep every product the solver and the energy books form
/// finite: the largest current is kMaxEmf / kMinResistance = 1e12 A, its
/// power 1e18 W; the largest stored energy q^2 / 2C at 1 pF is 5e35 J. (A
/// value of 1e200 V passed the finite check, then its power, 1e406 W,
/// overflowed.)
/// emf, V (either sign): a megavolt, beyond any battery or generator on a bench.
inline constexpr double kMaxEmf = 1e6;
/// resistance, internal_resistance, contact_resistance, Ohm: a teraohm (an
/// insulator); with kMinResistance the ratio is 1e18, all that double's
/// 16 digits can tell apart in one circuit anyway.
inline constexpr double kMaxResistance = 1e12;
/// inductance, H: a kilohenry (the largest iron-cored chokes are tens of H).
inline constexpr double kMaxInductance = 1e3;
/// capacitance, F: 10 kF (supercapacitors reach a few kF).
inline constexpr double kMaxCapacitance = 1e4;
/// plate_charge, C (either sign): bounded well above what the resolver itself
/// can put there (kMaxCapacitance at kMaxEmf is 1e10 C), since a save holds
/// the charge it wrote and is checked against the same bound when loaded.
inline constexpr double kMaxCharge = 1e12;

/// A capacitor below this capacitance, F, is an open gap (no branch): its
/// companion impedance h / 2C would exceed 1e8 Ohm at a 1 ms substep and cost
/// the solve its digits next to micro-ohm wires.
inline constexpr double kMinCapacitance = 1e-12;
/// Lamps (the light resolver's parts, docs/light.md): the property that marks
/// one, its luminous efficacy in lm per electrical W. Of a lamp's power, the
/// share efficacy / kLumensPerLightWatt is visible light: electricity books
/// it as the transfer "light" instead of heat (docs/energy.md, "Light").
inline constexpr const char* kLampEfficacy = "luminous_efficacy";
/// Lumens per watt of light at 555 nm, the most a watt of light can give (the
/// SI's definition of the lumen): luminous efficiency = efficacy / 683.
inline constexpr double kLumensPerLightWatt = 683;

/// Settings of the `electricity` plugin.
struct ElectricityConfig {
  /// A part or wire is `powered` when |current| exceeds this, A.
  double powered_threshold = 1e-3;
  /// Resistance of a touching contact when neither part carries
  /// `contact_resistance`, Ohm: each side contributes half.
  double contact_resistance = 1e-3;
  /// Resistance of a wire that does not carry `resistance`, Ohm (about 30 cm
  /// of 0.5 mm^2 copper with its terminals).
  double wire_resistance = 0.01;
  /// Internal resistance of a battery that does not carry `internal_resistance`, Ohm
  /// (a fresh alkaline cell).
  double internal_resistance = 0.1;
  /// Trapezoidal substeps per advance: the coil and capacitor models' error
  /// is second order in dt / substeps. 4 keeps a kit coil's rise (L/R ~ 10
  /// ms, 2.4 steps of 1/240 s) within 0.1 % of the analytic curve; a substep
  /// costs one back-substitution per driven circuit (docs/electricity.md).
  int substeps = 4;
  /// Components with at most this many unknowns are solved with dense LU,
  /// larger ones with sparse LU.
  std::int64_t dense_limit = 64;
  /// Publish each coil's `current_rate` (dI/dt at the end of the advance,
  /// A/s): on by default, since magnetism_from_electricity predicts a coil's
  /// current with it for the step whose force it makes (the magnet-coil
  /// coupling's energy balance, docs/magnetism.md); see the header.
  bool rates = true;
  /// The induction coupling's timing (docs/magnetism.md "The coupling's
  /// timing"): 2 (the default since session 17) commands the current of the
  /// rigid body's kick (one step on) and moves the parts on with the
  /// acceleration of their last step: second order. 1 (sessions 14-16)
  /// commands the force's current predicted 1.5 steps on and moves the parts
  /// on with their present velocity for the EMF: first order (the
  /// work-precision row's 0.7). Read by electricity_from_magnetism and
  /// magnetism_from_electricity too (kDefaultInductionOrder).
  int induction_order = kDefaultInductionOrder;

  /// Reads and validates the plugin settings; InputError names the bad key.
  static ElectricityConfig from(const PluginSettings& settings);
  /// The setting keys `from` accepts.
  static const std::vector<std::string>& keys();
};

/// What an electrical part is, by the properties it carries (first match wins:
/// a wire is never a part; then emf, inductance, capacitance, switch_closed,
/// resistance).
enum class PartKind : std::uint8_t { Node, Battery, Coil, Capacitor, Switch, Resistor };

class ElectricityResolver final : public Resolver {
 public:
  explicit ElectricityResolver(ElectricityConfig config = {});

  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  /// Contacts, reported loop states and the integrators' history (each
  /// coil's v_L and series EMF, each capacitor's last current, the batteries'
  /// last emfs, the guard flag) with the network they were built for: the
  /// restored resolver carries them over at its first network build when
  /// that network is the same, as the uninterrupted one would (docs/saves.md).
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;
  /// Battery work, I^2 R heat, switching losses, the EMF's work
  /// (transfer "magnetism"), the coils' and capacitors' energy (docs/energy.md).
  /// The flows are booked from the first call on (a ledger opened mid-run
  /// sees those since it opened).
  void report_energy(const WorldView& view, EnergyReport& out) override;

  // --- interaction functions: queued, performed in the next advance -------------
  /// Joins terminal `terminal_a` of part a to terminal `terminal_b` of part b
  /// through a contact resistance. Connecting a connected pair again only
  /// updates its terminals. Pairs of which either object is not (or no longer)
  /// an electrical part carry nothing.
  void connect(ObjectId a, ObjectId b, int terminal_a = 0, int terminal_b = 0);
  /// Breaks the contact between a and b, if there is one.
  void disconnect(ObjectId a, ObjectId b);
  /// Induction (Faraday): over the next advance only, coil `coil` carries an
  /// EMF of `emf` volts in its branch, driving current from terminal 0 to 1
  /// (-dPhi/dt from electricity_from_magnetism). The last command before an
  /// advance wins; an advance with no command has none. A command for an
  /// object that is not (or no longer) a coil, or with a non-finite value,
  /// does nothing.
  /// `step_mean`: the EMF's mean over the advance, V (-dPhi/dt over the
  /// step, the flux's change along the parts' predicted motion): the ramp
  /// to `emf` is then offset by a constant so that its mean is this. NaN
  /// (the default): the ramp alone.
  void set_induced_emf(ObjectId coil, double emf,
                       double step_mean = std::numeric_limits<double>::quiet_NaN());
  /// The induced EMF of coil `coil` at the end of the last advance, V (0 if none).
  double induced_emf(ObjectId coil) const;
  /// A resistor whose resistance something else decides (a photocell, from
  /// electricity_from_light): over the next advance only, resistor `part`
  /// has `ohms` instead of its `resistance` property. The last command before
  /// an advance wins; an advance with no command uses the property. A command
  /// for an object that is not a resistor, or with a negative or non-finite
  /// value, does nothing. A changed value is a new network (refactorised,
  /// with a guard step, as an edited `resistance` is).
  void set_resistance(ObjectId part, double ohms);
  /// The resistance set_resistance sent for `part` for the last advance,
  /// Ohm, or a negative number if none was (then a resistor used its property).
  double set_resistance_of(ObjectId part) const;
  /// Mutual inductance (a transformer): over the next advance only, coils a
  /// and b share M henries, so that a's inductive voltage is L_a dI_a/dt +
  /// M dI_b/dt and b's likewise (currents from terminal 0 to 1). Solved
  /// implicitly with the coils' own companion models (docs/electricity.md
  /// "Mutual inductance"). |M| is held below 0.99 sqrt(L_a L_b) (a coupling
  /// of 1 or more has no stable solution). The last command for a pair before
  /// an advance wins; an advance with none has no coupling. Commands naming a
  /// non-coil, the same coil twice or a non-finite M do nothing.
  void set_mutual_inductance(ObjectId a, ObjectId b, double henries);
  /// The mutual inductance of coils a and b in the last advance, H (0 if none).
  double mutual_inductance(ObjectId a, ObjectId b) const;

  // --- introspection (tests, tools) ---------------------------------------------
  /// Whether a and b touch electrically, as of the last advance.
  bool connected(ObjectId a, ObjectId b) const;
  std::size_t contact_count() const { return contacts_.size(); }
  /// Whether a two-terminal part lies on a closed loop, as of the last advance.
  bool closed(ObjectId element) const;
  /// Component factorisations so far: moves only when the network's matrix changes.
  std::uint64_t factorizations() const { return solver_.factorizations(); }
  /// Rebuilds of the network from properties (cheap; a rebuild that yields the
  /// same matrix does not factorise).
  std::uint64_t network_builds() const { return network_builds_; }
  /// Substep solves of the network since construction, and substeps whose
  /// sources were bit for bit those of the last solve, so that its answer
  /// was reused instead (tests; the benchmark).
  std::uint64_t solves() const { return solves_; }
  std::uint64_t solves_skipped() const { return solves_skipped_; }
  const MnaSolver& solver() const { return solver_; }
  /// The network last factorised (for the scaling benchmark).
  const Network& network() const { return network_; }
  const ElectricityConfig& config() const { return config_; }

 private:
  struct Command {
    bool connect;
    ObjectId a, b;
    int terminal_a, terminal_b;
  };
  struct Contact {
    int terminal_a = 0, terminal_b = 0;
  };
  struct Part {
    std::uint32_t slot;
    PartKind kind;
    std::uint32_t node[2];  // node of terminal 0 and 1 (equal for a node part)
    // Branch (battery, coil, capacitor) or conductance (resistor, closed
    // switch) index; -1 for a node, an open switch or a capacitor below
    // kMinCapacitance.
    std::int32_t element;
  };
  struct Wire {
    std::uint32_t slot;
    std::int32_t conductance;  // -1: an end is open
  };
  // Branch k's source each substep is e_k = companion + series emf; the
  // companion's history (v_l, previous current) is only valid while the
  // network stays the same: after a discontinuity the guard step rebuilds it
  // from the state alone.
  struct Coil {
    std::uint32_t slot;
    double inductance, resistance;
    double current = 0;  // the state: A, from terminal 0 to 1 through the coil
    /// Trapezoidal history: the inductor's own voltage L dI/dt at the last
    /// substep, V (V(0) - V(1) less R I and less series_emf).
    double v_l = 0;
    /// An EMF in series with the coil, V, driving current from terminal 0 to
    /// 1 (a source inside the branch): enters the branch's right-hand side in
    /// one place, the substep loop of advance(). Set at each substep on the
    /// ramp from its value at the advance's start to the induced EMF queued
    /// for the advance's end (set_induced_emf), zero without one.
    double series_emf = 0;
    /// 1/2 L I^2 (J) released this advance because the coil lost its last
    /// loop with current flowing (the spark at the opening contact).
    double released = 0;
    /// The part of series_emf held constant over the last advance, V: the
    /// induced EMF's mean over the step (set_induced_emf's `step_mean`) less
    /// the ramp's mean. State (saved): the next advance's ramp starts from
    /// series_emf less it.
    double emf_offset = 0;
    /// The coil's current at the last advance's end, A: magnetic_forces
    /// makes the coil's pull from it (coils_from_current), and the rigid
    /// body kicks the parts with that pull over the step this advance spans.
    /// A coil whose loop opens at this advance's start still pulls over it;
    /// book_substep books that work (the books only: it changes no current).
    double force_current = 0;
  };
  struct Capacitor {
    std::uint32_t slot;
    double capacitance, resistance;  // F (>= kMinCapacitance), series resistance Ohm
    double charge = 0;   // the state: C on the plate at terminal 0; V(0) - V(1) = q / C + R I
    double current = 0;  // trapezoidal history: A from terminal 0 to 1, last substep
  };

  void perform_commands(const WorldView& view);
  /// Moves the queued induced EMFs into induced_emf_ (per coil of this network).
  void take_induced_emfs(const WorldView& view);
  /// Moves the queued set_resistance commands into resistance_override_;
  /// marks the network dirty if a value changed.
  void take_resistance_commands(const WorldView& view);
  bool inputs_changed(const WorldView& view) { return input_versions(view) != seen_versions_; }
  void build_network(const WorldView& view, double h);
  /// solver_.solve, with a solution that overflowed turned into an
  /// InputError that names the circuit's parts and its largest source.
  void solve(const WorldView& view, std::span<const double> e, std::span<double> potential,
             std::span<double> current) const;
  void write_outputs(ResolverAccess& access);
  void write_current_rates(ResolverAccess& access);
  /// Value and membership counters of the columns that define the network.
  static constexpr std::size_t kNetworkInputCount = 12;
  using InputVersions = std::array<std::uint64_t, 2 * kNetworkInputCount>;
  InputVersions input_versions(const WorldView& view);

  ElectricityConfig config_;
  std::vector<Command> queue_;
  std::map<std::pair<ObjectId, ObjectId>, Contact> contacts_;  // key (a, b) with a < b

  // The network, rebuilt from properties when an input changed.
  bool dirty_ = true;
  bool reload_coil_state_ = true;
  double h_ = 0;  // the substep the coil companions were built for, s
  /// The next substep is a guard step (two backward-Euler half-steps): set at
  /// the first advance, when the network or its element lists change, when
  /// an emf or a coil's current or a capacitor's charge was edited from
  /// outside. The trapezoidal rule rings after such a jump; backward Euler
  /// damps it and rebuilds the history from the state alone.
  bool guard_ = true;
  InputVersions seen_versions_{};
  std::array<PropertyId, kNetworkInputCount> input_ids_{};  // resolved at the first use
  bool input_ids_resolved_ = false;
  // The columns of every advance, resolved at the first use.
  PropertyRef current_id_{prop::kCurrent}, voltage_id_{prop::kVoltage}, powered_id_{prop::kPowered},
      emf_id_{prop::kEmf}, current_rate_id_{prop::kCurrentRate}, charge_id_{prop::kCharge};
  std::uint64_t network_builds_ = 0;
  Network network_;
  MnaSolver solver_;
  // Induction: the commands of the next advance, and per coil the EMF added
  // to its branch source in the last one (a separate term, kept out of the
  // companion model's own source).
  struct InducedCommand {
    ObjectId coil;
    double emf, step_mean;
  };
  std::vector<InducedCommand> induced_queue_;
  std::vector<double> induced_emf_;   // per coil, V: the value at the advance's end
  std::vector<double> induced_mean_;  // per coil, V: its mean over the advance (NaN: none)
  std::vector<double> emf_start_;  // per coil, V: the series EMF at the advance's start (scratch)
  // set_resistance: the commands of the next advance, and the values the
  // network was built with (slot -> Ohm), compared each advance.
  std::vector<std::pair<ObjectId, double>> resistance_queue_;
  std::map<std::uint32_t, double> resistance_override_;
  // Mutual inductance: the commands of the next advance, the pairs (coil
  // indices) of the last one, and the coupled coils' response to a unit
  // source in each other's branch (rebuilt every advance that has pairs).
  struct Mutual {
    std::uint32_t a, b;  // coil indices
    double m;            // H
  };
  std::vector<std::tuple<ObjectId, ObjectId, double>> mutual_queue_;
  std::vector<Mutual> mutual_;
  void take_mutual_inductances(const WorldView& view);
  // The coupled coils' unit responses (transfer) depend only on the
  // factorisation and on which coils are coupled, not on M or the sources:
  // kept from advance to advance while neither changes (the motor's two
  // coils: k solves an advance saved between commutations). Valid for the
  // network build numbered transfer_build_ (network_builds_), with these
  // coupled coil indices.
  std::vector<double> transfer_;  // k x k, column-major (Eigen's order)
  std::vector<std::uint32_t> transfer_coupled_;
  std::uint64_t transfer_build_ = 0;
  // Per substep scratch of the coupled solve, kept between advances.
  std::vector<double> free_potential_, free_current_, mutual_v_;
  std::vector<Part> parts_;
  std::vector<Wire> wires_;
  std::vector<Coil> coils_;               // branch index = batteries_.size() + coil index
  std::vector<Capacitor> capacitors_;     // branch index = after the coils
  std::vector<std::uint32_t> batteries_;  // slots; branch index = position
  std::vector<double> battery_emf_;       // the emfs of the last advance, V
  std::vector<bool> element_closed_;      // per part: on a closed loop (two-terminal parts)
  std::vector<bool> branch_on_loop_, conductance_on_loop_;  // per element: not a bridge
  std::vector<std::uint32_t> bridge_branches_;      // branches not on a loop (current exactly 0)
  std::vector<Conductance> loop_conductances_;      // the conductances on loops, in index order
  std::vector<std::uint8_t> node_reports_through_;  // per node: a node part reports its current
  // What the last events said, per element. Hashed: write_outputs looks up
  // every part each step, and a tree made that n log n.
  std::unordered_map<ObjectId, bool> reported_closed_;
  // reported_closed_ per part (parallel to parts_), so that a step looks up
  // nothing: the id it was read for, and 0 unknown, 1 open, 2 closed. Written
  // through to the map; cleared when the map is replaced (restore_state).
  std::vector<ObjectId> reported_cache_id_;
  std::vector<std::uint8_t> reported_cache_;
  // write_outputs' scratch, per node and per conductance (kept between steps).
  std::vector<double> through_, g_current_;
  std::vector<std::uint32_t> stale_outputs_;  // slots that carry outputs but are no longer parts
  // write_outputs' columns, filled in the order of output_slots_ (parts,
  // wires, stale slots; made for the network build numbered output_build_)
  // and written in one ColumnWriter call each; write_current_rates' likewise.
  std::vector<std::uint32_t> output_slots_, rate_slots_;
  std::uint64_t output_build_ = 0;
  std::vector<double> out_current_, out_voltage_, rate_values_;
  std::vector<std::uint8_t> out_powered_;

  // Per-solve results.
  std::vector<double> e_, potential_, branch_current_;
  // The sources of the solve whose answer potential_ and branch_current_
  // hold, while `solved_valid_`. A substep whose sources are the same bits
  // would get the same answer, so it is not solved again: a resistive
  // circuit solves once an advance, a settled one not at all. Invalid after
  // every build_network (a new factorisation, zeroed results).
  std::vector<double> solved_e_;
  bool solved_valid_ = false;
  std::uint64_t solves_ = 0, solves_skipped_ = 0;
  // restore_state: the history saved, applied after the first build_network.
  struct SavedHistory {
    bool guard = true;
    Network network;
    std::vector<std::uint32_t> batteries;
    std::vector<double> battery_emf;
    std::vector<Coil> coils;
    std::vector<Capacitor> capacitors;
  };
  std::unique_ptr<SavedHistory> restored_;
  void apply_restored();

  /// The energy books (report_energy): the state at a substep's start, and
  /// the sums since the last report, J.
  struct Books {
    std::vector<double> potential0, current0, v_l0, coil_current0, charge0, cap_current0;
    std::vector<double> emf0;  // per coil: the series EMF of the last solve, V
    double battery = 0, heat = 0, switching = 0, emf_work = 0, light = 0;
    /// The elements' state at a substep's start (potential0 and current0,
    /// the last answer, are kept by the substep itself).
    void begin(const std::vector<Coil>& coils, const std::vector<Capacitor>& capacitors);
  };
  Books books_;
  /// The books are kept only once a ledger asked (report_energy): they cost
  /// a pass over every element a substep, and without `--energy` nobody
  /// reads them. From then on every substep is booked.
  bool books_on_ = false;
  void book_substep(double trap, double hs);
  /// Moves the lamps' light out of this advance's heat (books_.light).
  void book_light(const WorldView& view, double dt);
  std::optional<PropertyId> efficacy_id_;  // kLampEfficacy, once registered
  bool lamps_seen_ = false;                // report "light" from the first lamp on
};

/// Registers the `electricity` resolver and its property types only (for
/// tools and tests that run circuits without the rigid body). The full set,
/// with the interactions that feed electricity, is register_electricity_plugins
/// in electricity_plugins.hpp.
void register_electricity_resolver(PluginRegistry& registry);

}  // namespace alloy::electricity
