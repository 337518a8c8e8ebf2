#include "resolvers/electricity/electricity.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "runtime/scope.hpp"

namespace alloy::electricity {

namespace {

PropertyDef number(const char* name, const char* unit, const char* doc,
                   std::optional<double> min = {}, std::optional<double> max = {}) {
  return {
      .name = name, .kind = PropertyKind::Number, .unit = unit, .doc = doc, .min = min, .max = max};
}

/// The columns that decide the network. `emf` counts by membership only
/// (which objects are batteries): its values enter the right-hand side alone,
/// read every step, so a new emf needs no new factorisation.
constexpr const char* kNetworkInputs[] = {
    prop::kConductive, prop::kInternalResistance, prop::kInductance,
    prop::kResistance, prop::kContactResistance,  prop::kWireFrom,
    prop::kWireTo,     prop::kWireFromTerminal,   prop::kWireToTerminal,
    prop::kEmf,        prop::kCapacitance,        prop::kSwitchClosed,
};

double positive_resistance(double r) {
  return std::max(r, kMinResistance);
}

}  // namespace

std::vector<PropertyDef> electricity_property_defs() {
  return {
      {.name = prop::kConductive,
       .kind = PropertyKind::Bool,
       .doc = "conducts electricity: touching conductive parts connect; without emf, inductance or "
              "resistance the part is one equipotential node"},
      number(prop::kEmf, "V", "battery: electromotive force from terminal 0 (-) to terminal 1 (+)",
             -kMaxEmf, kMaxEmf),
      number(prop::kInternalResistance, "Ohm", "battery: internal resistance (default 0.1)", 0.0,
             kMaxResistance),
      number(prop::kInductance, "H", "coil: self-inductance between terminals 0 and 1", 0.0,
             kMaxInductance),
      number(
          prop::kResistance, "Ohm",
          "resistor or coil: resistance between terminals 0 and 1; wire: end to end (default 0.01)",
          0.0, kMaxResistance),
      number(prop::kContactResistance, "Ohm",
             "resistance a touching contact on this part adds (default 0.0005 per side)", 0.0,
             kMaxResistance),
      {.name = prop::kWireFrom,
       .kind = PropertyKind::Ref,
       .doc = "this object is a wire: the part its first end is attached to"},
      {.name = prop::kWireTo,
       .kind = PropertyKind::Ref,
       .doc = "this object is a wire: the part its second end is attached to"},
      {.name = prop::kWireFromTerminal,
       .kind = PropertyKind::Integer,
       .doc = "terminal (0 or 1) of wire_from the wire is attached to (default 0)",
       .min = 0.0},
      {.name = prop::kWireToTerminal,
       .kind = PropertyKind::Integer,
       .doc = "terminal (0 or 1) of wire_to the wire is attached to (default 0)",
       .min = 0.0},
      number(
          prop::kCurrent, "A",
          "written by electricity: through a battery, coil, resistor or wire from terminal 0 to 1 "
          "(from wire_from to wire_to); through a node part, the total current passing it. A "
          "coil's "
          "current is its state"),
      number(prop::kVoltage, "V",
             "written by electricity: node part, potential against its circuit's ground; battery, "
             "V(1) - V(0); coil and resistor, V(0) - V(1); wire, V(from) - V(to)"),
      {.name = prop::kPowered,
       .kind = PropertyKind::Bool,
       .doc = "written by electricity: |current| is above the powered threshold (1 mA)"},
      number(prop::kCurrentRate, "A/s",
             "written by electricity with rates = true: a coil's dI/dt at the end of the step"),
      number(prop::kCapacitance, "F",
             "capacitor: capacitance between terminals 0 and 1 (below 1 pF: an open gap)", 0.0,
             kMaxCapacitance),
      number(prop::kCharge, "C",
             "capacitor: charge on the plate at terminal 0 (its state; kept across edits)",
             -kMaxCharge, kMaxCharge),
      {.name = prop::kSwitchClosed,
       .kind = PropertyKind::Bool,
       .doc = "switch: joins its terminals 0 and 1 through `resistance` (default: the contact "
              "resistance setting) while true; an open gap while false"},
  };
}

// --- settings ------------------------------------------------------------------

const std::vector<std::string>& ElectricityConfig::keys() {
  static const std::vector<std::string> k = {
      "powered_threshold", "contact_resistance", "wire_resistance", "internal_resistance",
      "substeps",          "dense_limit",        "rates",           "induction_order"};
  return k;
}

ElectricityConfig ElectricityConfig::from(const PluginSettings& s) {
  s.check_known(kResolverName, keys());
  ElectricityConfig c;
  c.powered_threshold = s.number("powered_threshold", c.powered_threshold);
  c.contact_resistance = s.number("contact_resistance", c.contact_resistance);
  c.wire_resistance = s.number("wire_resistance", c.wire_resistance);
  c.internal_resistance = s.number("internal_resistance", c.internal_resistance);
  c.substeps = int(s.integer("substeps", c.substeps));
  c.dense_limit = s.integer("dense_limit", c.dense_limit);
  c.rates = s.boolean("rates", c.rates);
  c.induction_order = int(s.integer("induction_order", c.induction_order));
  auto non_negative = [&](const char* key, double v) {
    if (!(v >= 0) || !std::isfinite(v))
      throw InputError(
          s.where, "electricity setting '" + std::string(key) + "' must be a finite number >= 0");
  };
  non_negative("powered_threshold", c.powered_threshold);
  non_negative("contact_resistance", c.contact_resistance);
  non_negative("wire_resistance", c.wire_resistance);
  non_negative("internal_resistance", c.internal_resistance);
  if (c.induction_order != 1 && c.induction_order != 2)
    throw InputError(s.where, "electricity setting 'induction_order' must be 1 or 2, not " +
                                  std::to_string(c.induction_order));
  if (c.substeps < 1 || c.substeps > 1000)
    throw InputError(s.where, "electricity setting 'substeps' must be between 1 and 1000");
  if (c.dense_limit < 0)
    throw InputError(s.where, "electricity setting 'dense_limit' must be >= 0");
  return c;
}

// --- the resolver ----------------------------------------------------------------

ElectricityResolver::ElectricityResolver(ElectricityConfig config)
    : config_(config), solver_(std::size_t(config.dense_limit)) {}

void ElectricityResolver::connect(ObjectId a, ObjectId b, int terminal_a, int terminal_b) {
  if (terminal_a < 0 || terminal_a > 1 || terminal_b < 0 || terminal_b > 1)
    throw AccessError("electricity: connect() takes terminals 0 or 1");
  if (a == b) return;  // a part touching itself joins nothing
  if (b < a) std::swap(a, b), std::swap(terminal_a, terminal_b);
  queue_.push_back({true, a, b, terminal_a, terminal_b});
}

void ElectricityResolver::disconnect(ObjectId a, ObjectId b) {
  if (a == b) return;
  if (b < a) std::swap(a, b);
  queue_.push_back({false, a, b, 0, 0});
}

bool ElectricityResolver::connected(ObjectId a, ObjectId b) const {
  if (b < a) std::swap(a, b);
  return contacts_.count({a, b}) != 0;
}

bool ElectricityResolver::closed(ObjectId element) const {
  auto it = reported_closed_.find(element);
  return it != reported_closed_.end() && it->second;
}

void ElectricityResolver::build(ResolverAccess& access) {
  // Called after any structural change in the world: the network is rebuilt
  // at the next advance (and refactorised only if its matrix changed).
  dirty_ = true;
  // Give every part and wire its output columns now, so that advance() only
  // ever changes values: a new membership would be a structural change, and
  // with it a rebuild of every resolver, on every step that makes one.
  auto current = access.writer<double>(prop::kCurrent);
  auto voltage = access.writer<double>(prop::kVoltage);
  auto powered = access.writer<std::uint8_t>(prop::kPowered);
  auto conductive = access.column<std::uint8_t>(prop::kConductive);
  auto give = [&](std::uint32_t slot) {
    if (!current.has(slot))
      current.set(slot, 0.0);  // a coil's preset current is its state: keep it
    if (!voltage.has(slot)) voltage.set(slot, 0.0);
    if (!powered.has(slot)) powered.set(slot, 0);
  };
  for (std::uint32_t s : conductive.members())
    if (conductive[s]) give(s);
  for (std::uint32_t s : access.column<double>(prop::kEmf).members()) give(s);
  for (std::uint32_t s : access.column<double>(prop::kInductance).members()) give(s);
  for (std::uint32_t s : access.column<std::uint8_t>(prop::kSwitchClosed).members()) give(s);
  {
    auto charge = access.writer<double>(prop::kCharge);
    for (std::uint32_t s : access.column<double>(prop::kCapacitance).members()) {
      give(s);
      if (!charge.has(s)) charge.set(s, 0.0);  // a preset charge is the state: keep it
    }
  }
  for (std::uint32_t s : access.column<ObjectId>(prop::kWireFrom).members()) give(s);
  for (std::uint32_t s : access.column<ObjectId>(prop::kWireTo).members()) give(s);
  if (config_.rates) {
    auto rate = access.writer<double>(prop::kCurrentRate);
    for (std::uint32_t s : access.column<double>(prop::kInductance).members())
      if (!rate.has(s)) rate.set(s, 0.0);
  }
}

ElectricityResolver::InputVersions ElectricityResolver::input_versions(const WorldView& view) {
  static_assert(std::size(kNetworkInputs) == kNetworkInputCount);
  if (!input_ids_resolved_) {
    for (std::size_t i = 0; i < kNetworkInputCount; ++i)
      input_ids_[i] = view.property(kNetworkInputs[i]);
    input_ids_resolved_ = true;
  }
  InputVersions v{};
  for (std::size_t i = 0; i < kNetworkInputCount; ++i) {
    const ColumnBase& c = view.store().column(input_ids_[i]);
    // emf values enter only the right-hand side; its membership is structural.
    v[2 * i] = input_ids_[i] == emf_id_(view) ? 0 : c.version();
    v[2 * i + 1] = c.membership_version();
  }
  return v;
}

void ElectricityResolver::perform_commands(const WorldView& view) {
  const PropertyStore& store = view.store();
  for (const Command& c : queue_) {
    if (!store.alive(c.a) || !store.alive(c.b))
      continue;  // a part destroyed since the command was queued
    const auto key = std::make_pair(c.a, c.b);
    auto it = contacts_.find(key);
    if (c.connect) {
      if (it == contacts_.end()) {
        contacts_.emplace(key, Contact{c.terminal_a, c.terminal_b});
        view.emit({.type = event::kConnected, .a = c.a, .b = c.b});
        dirty_ = true;
      } else if (it->second.terminal_a != c.terminal_a || it->second.terminal_b != c.terminal_b) {
        it->second = {c.terminal_a, c.terminal_b};
        dirty_ = true;
      }
    } else if (it != contacts_.end()) {
      contacts_.erase(it);
      view.emit({.type = event::kDisconnected, .a = c.a, .b = c.b});
      dirty_ = true;
    }
  }
  queue_.clear();
}

void ElectricityResolver::build_network(const WorldView& view, double h) {
  ++network_builds_;
  solved_valid_ = false;  // first: a build that throws leaves nothing to reuse either
  h_ = h;
  const PropertyStore& store = view.store();
  const auto conductive = view.column<std::uint8_t>(prop::kConductive);
  const auto emf = view.column<double>(prop::kEmf);
  const auto internal_r = view.column<double>(prop::kInternalResistance);
  const auto inductance = view.column<double>(prop::kInductance);
  const auto resistance = view.column<double>(prop::kResistance);
  const auto contact_r = view.column<double>(prop::kContactResistance);
  const auto wire_from = view.column<ObjectId>(prop::kWireFrom);
  const auto wire_to = view.column<ObjectId>(prop::kWireTo);
  const auto from_terminal = view.column<std::int64_t>(prop::kWireFromTerminal);
  const auto to_terminal = view.column<std::int64_t>(prop::kWireToTerminal);
  const auto capacitance = view.column<double>(prop::kCapacitance);
  const auto switch_closed = view.column<std::uint8_t>(prop::kSwitchClosed);

  // Which slots are wires, which are parts, and of what kind.
  const std::size_t slots = store.slot_count();
  std::vector<std::uint8_t> is_wire(slots, 0), is_part(slots, 0);
  for (std::uint32_t s : wire_from.members()) is_wire[s] = 1;
  for (std::uint32_t s : wire_to.members()) is_wire[s] = 1;
  for (std::uint32_t s : conductive.members()) is_part[s] |= conductive[s] != 0;
  for (std::uint32_t s : emf.members()) is_part[s] = 1;
  for (std::uint32_t s : inductance.members()) is_part[s] = 1;
  for (std::uint32_t s : capacitance.members()) is_part[s] = 1;
  for (std::uint32_t s : switch_closed.members()) is_part[s] = 1;

  Network net;
  parts_.clear();
  wires_.clear();
  std::vector<std::uint32_t> batteries;
  std::vector<Coil> coils;
  std::vector<Capacitor> capacitors;
  std::vector<std::int32_t> part_of_slot(slots, -1);
  for (std::uint32_t s = 0; s < slots; ++s) {
    if (!is_part[s] || is_wire[s]) continue;
    Part p{s, PartKind::Node, {net.node_count, net.node_count}, -1};
    if (emf.has(s))
      p.kind = PartKind::Battery;
    else if (inductance.has(s))
      p.kind = PartKind::Coil;
    else if (capacitance.has(s))
      p.kind = PartKind::Capacitor;
    else if (switch_closed.has(s))
      p.kind = PartKind::Switch;
    else if (resistance.has(s))
      p.kind = PartKind::Resistor;
    if (p.kind == PartKind::Node)
      net.node_count += 1;
    else
      p.node[1] = net.node_count + 1, net.node_count += 2;
    part_of_slot[s] = std::int32_t(parts_.size());
    parts_.push_back(p);
  }

  // Thevenin branches: batteries first, so that a component's ground is the
  // negative terminal of its first battery; then coils and capacitors. Their
  // companions (docs/electricity.md) have the same impedance for the
  // trapezoidal rule over h and backward Euler over h/2: coil z = R + 2L/h,
  // capacitor z = R + h/2C, so the guard step needs no factorisation of its own.
  for (Part& p : parts_)
    if (p.kind == PartKind::Battery) {
      p.element = std::int32_t(net.branches.size());
      batteries.push_back(p.slot);
      net.branches.push_back(
          {p.node[0], p.node[1],
           positive_resistance(internal_r.value_or(p.slot, config_.internal_resistance))});
    }
  for (Part& p : parts_)
    if (p.kind == PartKind::Coil) {
      const double l = inductance[p.slot];
      const double r = resistance.value_or(p.slot, 0.0);
      p.element = std::int32_t(net.branches.size());
      coils.push_back({.slot = p.slot, .inductance = l, .resistance = r});
      net.branches.push_back({p.node[0], p.node[1], positive_resistance(r + 2 * l / h)});
    }
  for (Part& p : parts_)
    if (p.kind == PartKind::Capacitor && capacitance[p.slot] >= kMinCapacitance) {
      const double c = capacitance[p.slot];
      const double r = resistance.value_or(p.slot, 0.0);
      p.element = std::int32_t(net.branches.size());
      capacitors.push_back({.slot = p.slot, .capacitance = c, .resistance = r});
      net.branches.push_back({p.node[0], p.node[1], positive_resistance(r + h / (2 * c))});
    }
  for (Part& p : parts_)
    if (p.kind == PartKind::Resistor ||
        (p.kind == PartKind::Switch && switch_closed[p.slot] != 0)) {
      double r = p.kind == PartKind::Resistor
                     ? resistance[p.slot]
                     : resistance.value_or(p.slot, config_.contact_resistance);
      if (p.kind == PartKind::Resistor)
        if (auto it = resistance_override_.find(p.slot); it != resistance_override_.end())
          r = it->second;
      p.element = std::int32_t(net.conductances.size());
      net.conductances.push_back({p.node[0], p.node[1], 1.0 / positive_resistance(r)});
    }

  // Wires: an end on a destroyed object (or a null ref) is open; an end on a
  // live object that is not an electrical part is a scene error.
  auto end_node = [&](std::uint32_t wire, ObjectId target, std::int64_t terminal,
                      const char* which) -> std::int64_t {
    if (terminal < 0 || terminal > 1)
      throw InputError(
          ErrorLocation{"", 0, store.describe(store.id_at(wire))},
          std::string(which) + "_terminal must be 0 or 1, got " + std::to_string(terminal));
    if (target.is_null() || !store.alive(target)) return -1;
    // A part out of this stage's scope (frozen for a value it could not
    // carry, World::frozen, or in another area) is not in the network: the
    // wire's end is open, as on a destroyed part, rather than a scene error
    // that would blame the wire for the part's fault.
    if (view.scope() && !view.scope()->contains(target.index)) return -1;
    const std::int32_t pi = target.index < slots ? part_of_slot[target.index] : -1;
    if (pi < 0)
      throw InputError(
          ErrorLocation{"", 0, store.describe(store.id_at(wire))},
          std::string(which) + " is '" + store.describe(target) +
              "', which is not an electrical part " +
              (is_wire[target.index] ? "(it is a wire: wires join parts)"
                                     : "(give it conductive = true, emf or inductance)"));
    return parts_[std::size_t(pi)].node[terminal];
  };
  for (std::uint32_t s = 0; s < slots; ++s) {
    if (!is_wire[s]) continue;
    const std::int64_t a =
        end_node(s, wire_from.value_or(s, ObjectId{}), from_terminal.value_or(s, 0), "wire_from");
    const std::int64_t b =
        end_node(s, wire_to.value_or(s, ObjectId{}), to_terminal.value_or(s, 0), "wire_to");
    Wire w{s, -1};
    if (a >= 0 && b >= 0) {
      w.conductance = std::int32_t(net.conductances.size());
      net.conductances.push_back(
          {std::uint32_t(a), std::uint32_t(b),
           1.0 / positive_resistance(resistance.value_or(s, config_.wire_resistance))});
    }
    wires_.push_back(w);
  }

  // Contacts: dropped when an object is gone; kept but inert while either
  // object is not an electrical part (it may become one).
  for (auto it = contacts_.begin(); it != contacts_.end();) {
    const auto [a, b] = it->first;
    if (!store.alive(a) || !store.alive(b)) {
      it = contacts_.erase(it);
      continue;
    }
    const std::int32_t pa = part_of_slot[a.index], pb = part_of_slot[b.index];
    if (pa >= 0 && pb >= 0) {
      const double half = config_.contact_resistance / 2;
      const double r = contact_r.value_or(a.index, half) + contact_r.value_or(b.index, half);
      net.conductances.push_back({parts_[std::size_t(pa)].node[it->second.terminal_a],
                                  parts_[std::size_t(pb)].node[it->second.terminal_b],
                                  1.0 / positive_resistance(r)});
    }
    ++it;
  }

  // Which elements lie on a closed loop. One that does not (a bridge of the
  // network graph) carries exactly zero current by Kirchhoff's current law
  // across the cut it spans; the solver gives zero only to rounding, so its
  // current is set to exact zero after each solve (a dead circuit then reads
  // 0, not 1e-14, and an opened coil's state is exactly 0).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(net.branches.size() + net.conductances.size());
  for (const auto& br : net.branches) edges.emplace_back(br.a, br.b);
  for (const auto& g : net.conductances) edges.emplace_back(g.a, g.b);
  const std::vector<bool> on_cycle = edges_on_cycles(net.node_count, edges);
  branch_on_loop_.assign(on_cycle.begin(), on_cycle.begin() + std::ptrdiff_t(net.branches.size()));
  conductance_on_loop_.assign(on_cycle.begin() + std::ptrdiff_t(net.branches.size()),
                              on_cycle.end());
  // The same facts as lists, for the loops of every substep: the bridges
  // (usually none or a few) whose current is set to zero, and the
  // conductances on loops whose heat the books take, in index order (the
  // order of the sums, so the same bits as a scan of every conductance).
  bridge_branches_.clear();
  for (std::uint32_t k = 0; k < net.branches.size(); ++k)
    if (!on_cycle[k]) bridge_branches_.push_back(k);
  loop_conductances_.clear();
  for (std::size_t k = 0; k < net.conductances.size(); ++k)
    if (on_cycle[net.branches.size() + k]) loop_conductances_.push_back(net.conductances[k]);
  element_closed_.assign(parts_.size(), false);
  // write_outputs sums the current passing a node only where a node part
  // (a bar, a contact) reports it: not at the terminals of every element.
  node_reports_through_.assign(net.node_count, 0);
  for (const Part& p : parts_)
    if (p.kind == PartKind::Node) node_reports_through_[p.node[0]] = 1;
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    const Part& p = parts_[i];
    if (p.element < 0) continue;  // a node, an open switch, a vanishing capacitor
    if (p.kind == PartKind::Battery || p.kind == PartKind::Coil || p.kind == PartKind::Capacitor)
      element_closed_[i] = on_cycle[std::size_t(p.element)];
    else
      element_closed_[i] = on_cycle[net.branches.size() + std::size_t(p.element)];
  }

  // Objects that still carry our outputs but are no longer parts or wires
  // (a battery whose emf was removed) are zeroed, not left showing old values.
  stale_outputs_.clear();
  for (std::uint32_t s : view.column<double>(prop::kCurrent).members())
    if (part_of_slot[s] < 0 && !is_wire[s]) stale_outputs_.push_back(s);
  for (auto it = reported_closed_.begin(); it != reported_closed_.end();)
    it = store.alive(it->first) ? std::next(it) : reported_closed_.erase(it);

  // The integrators' history survives a rebuild that changed nothing (a
  // structural change elsewhere in the world): same matrix, same batteries,
  // coils and capacitors in the same order. Anything else is a discontinuity
  // and the next substep is a guard step, which needs the state alone.
  auto same_slots = [](const auto& a, const auto& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                      [](const auto& x, const auto& y) { return x.slot == y.slot; });
  };
  const bool same = net == network_ && batteries == batteries_ && same_slots(coils, coils_) &&
                    same_slots(capacitors, capacitors_);
  if (same) {
    for (std::size_t i = 0; i < coils.size(); ++i)
      coils[i].current = coils_[i].current, coils[i].v_l = coils_[i].v_l,
      coils[i].series_emf = coils_[i].series_emf, coils[i].emf_offset = coils_[i].emf_offset;
    for (std::size_t i = 0; i < capacitors.size(); ++i)
      capacitors[i].charge = capacitors_[i].charge, capacitors[i].current = capacitors_[i].current;
  } else {
    guard_ = true;
    battery_emf_.assign(batteries.size(), 0.0);
  }
  // The current the coil's pull was made from belongs to the coil, not to
  // its network: it outlives an opened loop, which is when book_substep
  // needs it.
  // By slot, in linear time (a network may have thousands of coils).
  if (!coils_.empty()) {
    std::uint32_t top = 0;
    for (const Coil& old : coils_) top = std::max(top, old.slot);
    std::vector<std::int32_t> old_of_slot(std::size_t(top) + 1, -1);
    for (std::size_t k = 0; k < coils_.size(); ++k) old_of_slot[coils_[k].slot] = std::int32_t(k);
    for (Coil& c : coils)
      if (c.slot <= top && old_of_slot[c.slot] >= 0) {
        const Coil& old = coils_[std::size_t(old_of_slot[c.slot])];
        c.force_current = old.force_current;
      }
  }
  batteries_ = std::move(batteries);
  coils_ = std::move(coils);
  capacitors_ = std::move(capacitors);

  // The expensive part, only when the matrix changed.
  if (!(net == network_)) solver_.factor(net);
  network_ = std::move(net);
  e_.assign(network_.branches.size(), 0.0);
  // A rebuild that changed nothing keeps the last substep's solution with
  // the history: the energy books take each trapezoidal substep's start
  // values from it, and zeros there booked half of the first substep's
  // battery work and wire heat as nothing (adv13's F8: a transformer
  // switched on at t = 0 left 0.44 % of the energy moved at 1/240 s). The
  // solution is not an input of the solve: no state changes.
  if (!same || potential_.size() != network_.node_count ||
      branch_current_.size() != network_.branches.size()) {
    potential_.assign(network_.node_count, 0.0);
    branch_current_.assign(network_.branches.size(), 0.0);
  }
  seen_versions_ = input_versions(view);
  dirty_ = false;
}

void ElectricityResolver::advance(ResolverAccess& access, double dt) {
  perform_commands(access);
  take_resistance_commands(access);
  const double h = dt / config_.substeps;
  if (dirty_ || h != h_ || inputs_changed(access)) build_network(access, h);
  if (restored_) apply_restored();

  // The state is in properties (written at the end of every advance, or
  // edited from outside): a coil's `current`, a capacitor's `plate_charge`.
  // Reading it here makes a rebuild, a swap or an edit lose nothing; a value
  // other than the one last written is an edit, a jump the guard step absorbs.
  const auto current = current_id_.column<double>(access);
  for (Coil& c : coils_) {
    const double i = current.value_or(c.slot, 0.0);
    if (i != c.current) guard_ = true, c.current = i, c.v_l = 0;
  }
  const auto charge = charge_id_.column<double>(access);
  for (Capacitor& c : capacitors_) {
    const double q = charge.value_or(c.slot, 0.0);
    if (q != c.charge) guard_ = true, c.charge = q, c.current = 0;
  }
  const auto emf = emf_id_.column<double>(access);
  const std::size_t nb = batteries_.size(), nc = coils_.size();
  for (std::size_t k = 0; k < nb; ++k) {
    const double e = emf[batteries_[k]];
    if (e != battery_emf_[k]) guard_ = true;  // a source that steps is a discontinuity too
    battery_emf_[k] = e_[k] = e;
  }
  // A coil that lost its last loop while carrying current: KCL stops it at
  // the first substep; its field's energy goes into the gap (the spark of a
  // real switch), which the model does not follow. It is reported.
  for (std::size_t i = 0; i < nc; ++i) {
    Coil& c = coils_[i];
    c.released = branch_on_loop_[nb + i] ? 0.0 : 0.5 * c.inductance * c.current * c.current;
  }

  // Induction: the EMF queued for this advance (electricity_from_magnetism)
  // is a source in series with its coil, held over the advance's substeps.
  // The EMF is queued for the advance's end (the flux rate one step on) and
  // ramps linearly over the substeps from the one in force at the last
  // substep's end, so that the trapezoidal rule integrates a piecewise
  // linear EMF exactly: its integral is the flux's change over the step, to
  // second order (docs/electricity.md "Induction").
  //
  // With a step mean (electricity_from_magnetism's -dPhi/dt over the step,
  // the flux's change along the motion), the ramp is offset by a constant
  // over the advance so that the EMF's mean over the step is exactly that:
  // the flux the circuit integrates is then the flux the parts' motion
  // changes, step after step (docs/magnetism.md "The coupling's timing"),
  // and the trapezoidal rule's mean EMF times its mean current is the
  // work of the coil's pull along the motion. The offset steps at the
  // advance's start: the inductor's voltage takes the step (the branch's
  // voltage is continuous), in the history as in the books.
  take_induced_emfs(access);
  emf_start_.resize(nc);
  for (std::size_t i = 0; i < nc; ++i) {
    Coil& c = coils_[i];
    emf_start_[i] = c.series_emf - c.emf_offset;
    const double mean = induced_mean_[i];
    double offset = std::isfinite(mean) ? mean - 0.5 * (emf_start_[i] + induced_emf_[i]) : 0.0;
    if (!std::isfinite(offset)) offset = 0.0;
    const double jump = offset - c.emf_offset;
    c.emf_offset = offset;
    if (jump == 0) continue;
    if (branch_on_loop_[nb + i]) c.v_l += jump;
    c.series_emf += jump;
    if (books_.emf0.size() > i) books_.emf0[i] += jump;
  }
  // Mutual inductance: coil i's companion gains sum_j (2 M_ij / h)(I_j' - I_j).
  // The known part goes into its source; the unknown currents are solved by
  // superposition: with T the coupled coils' currents per unit source in each
  // other's branch, (1 + (2/h) T M) I'_C = I0_C, then one solve with the
  // coupling sources known (docs/electricity.md "Mutual inductance").
  take_mutual_inductances(access);
  std::vector<std::uint32_t> coupled;  // coil indices
  Eigen::MatrixXd mutual_m;
  if (!mutual_.empty()) {
    std::vector<std::int32_t> index(nc, -1);
    for (const Mutual& m : mutual_)
      for (std::uint32_t c : {m.a, m.b})
        if (index[c] < 0) index[c] = std::int32_t(coupled.size()), coupled.push_back(c);
    const std::size_t k = coupled.size();
    mutual_m = Eigen::MatrixXd::Zero(k, k);
    for (const Mutual& m : mutual_)
      mutual_m(index[m.a], index[m.b]) = mutual_m(index[m.b], index[m.a]) = m.m;
    // The unit responses depend on the factorisation and the coupled set
    // alone: solved again only after a network build (a commutation, a new
    // step) or when other coils are coupled. Same solves, same bits.
    if (transfer_build_ != network_builds_ || transfer_coupled_ != coupled) {
      transfer_.assign(k * k, 0.0);
      // Unit responses go to scratch vectors: potential_ and branch_current_
      // stay the last substep's (the energy books start from them).
      std::vector<double> unit(e_.size(), 0.0), unit_potential(potential_.size()),
          unit_current(branch_current_.size());
      for (std::size_t col = 0; col < k; ++col) {
        unit.assign(e_.size(), 0.0);
        unit[nb + coupled[col]] = 1.0;
        solve(access, unit, unit_potential, unit_current);
        for (std::size_t row = 0; row < k; ++row)
          if (branch_on_loop_[nb + coupled[row]])
            transfer_[col * k + row] = unit_current[nb + coupled[row]];
      }
      transfer_build_ = network_builds_, transfer_coupled_ = coupled;
    }
  }
  const Eigen::Map<const Eigen::MatrixXd> transfer(transfer_.data(), Eigen::Index(coupled.size()),
                                                   Eigen::Index(coupled.size()));
  // (1 + (2/h) T M) is the same in every substep of the advance (h, T and M
  // are held): factorised once here, not once a substep.
  Eigen::PartialPivLU<Eigen::MatrixXd> coupled_system;
  if (!coupled.empty())
    coupled_system.compute(
        Eigen::MatrixXd::Identity(Eigen::Index(coupled.size()), Eigen::Index(coupled.size())) +
        (2 / h) * transfer * mutual_m);
  free_potential_.resize(potential_.size()), free_current_.resize(branch_current_.size());

  // Each substep is one trapezoidal step over h, or, as the guard after a
  // discontinuity, two backward-Euler steps over h/2 (same impedances, so the
  // same factorisation). With `trap` = 1 or 0:
  //   coil       v_L' + trap v_L = (2L/h)(I' - I)           e = (2L/h) I + trap v_L + series_emf
  //   capacitor  q' = q + (h/2)(I' + trap I)                 e = -(q/C + trap (h/2C) I)
  // (branch law V(0) - V(1) = z I' - e; docs/electricity.md derives both).
  auto substep = [&](double trap) {
    for (std::size_t i = 0; i < nc; ++i) {
      const Coil& c = coils_[i];
      e_[nb + i] = 2 * c.inductance / h * c.current + trap * c.v_l + c.series_emf;
    }
    for (std::size_t j = 0; j < capacitors_.size(); ++j) {
      const Capacitor& c = capacitors_[j];
      e_[nb + nc + j] = -(c.charge / c.capacitance + trap * h / (2 * c.capacitance) * c.current);
    }
    if (books_on_) books_.begin(coils_, capacitors_);
    const std::size_t k = coupled.size();
    Eigen::VectorXd before(k), after(k);
    if (k > 0) {
      for (std::size_t a = 0; a < k; ++a) before[a] = coils_[coupled[a]].current;
      const Eigen::VectorXd known = (2 / h) * (mutual_m * before);
      for (std::size_t a = 0; a < k; ++a) e_[nb + coupled[a]] += known[a];
      solve(access, e_, free_potential_, free_current_);
      Eigen::VectorXd i0(k);
      for (std::size_t a = 0; a < k; ++a)
        i0[a] = branch_on_loop_[nb + coupled[a]] ? free_current_[nb + coupled[a]] : 0.0;
      after = coupled_system.solve(i0);
      const Eigen::VectorXd coupling = -(2 / h) * (mutual_m * after);
      for (std::size_t a = 0; a < k; ++a) e_[nb + coupled[a]] += coupling[a];
    }
    // The same sources, bit for bit, as the solve whose answer we hold: the
    // same answer (the factor is the same until build_network), so reuse it.
    // The books start from the last answer: kept by swapping buffers (the
    // solve overwrites every potential and every current), copied only when
    // the answer is reused.
    if (solved_valid_ && solved_e_.size() == e_.size() &&
        std::memcmp(solved_e_.data(), e_.data(), e_.size() * sizeof(double)) == 0) {
      ++solves_skipped_;
      if (books_on_) books_.potential0 = potential_, books_.current0 = branch_current_;
    } else {
      solved_valid_ = false;  // until the solve below succeeds
      std::swap(books_.potential0, potential_), std::swap(books_.current0, branch_current_);
      potential_.resize(books_.potential0.size()), branch_current_.resize(books_.current0.size());
      solve(access, e_, potential_, branch_current_);
      for (std::uint32_t k : bridge_branches_) branch_current_[k] = 0.0;
      solved_e_ = e_;
      solved_valid_ = true;
      ++solves_;
    }
    // The mutual part of each coupled coil's inductive voltage.
    std::vector<double>& mutual_v = mutual_v_;
    mutual_v.assign(k > 0 ? nc : 0, 0.0);
    for (std::size_t a = 0; a < k; ++a)
      for (std::size_t b = 0; b < k; ++b)
        if (a != b) mutual_v[coupled[a]] += 2 / h * mutual_m(a, b) * (after[b] - before[b]);
    for (std::size_t i = 0; i < nc; ++i) {
      Coil& c = coils_[i];
      const double next = branch_current_[nb + i];
      // An opened coil carries no current and has no dI/dt: its history is 0
      // (left to the formula, it would alternate in sign forever).
      c.v_l = branch_on_loop_[nb + i] ? 2 * c.inductance / h * (next - c.current) +
                                            (k > 0 ? mutual_v[i] : 0.0) - trap * c.v_l
                                      : 0.0;
      c.current = next;
    }
    for (std::size_t j = 0; j < capacitors_.size(); ++j) {
      Capacitor& c = capacitors_[j];
      const double next = branch_current_[nb + nc + j];
      c.charge += h / 2 * (next + trap * c.current);
      c.current = next;
    }
    if (books_on_) book_substep(trap, trap > 0 ? h : h / 2);
  };
  for (int step = 0; step < config_.substeps; ++step) {
    const double along = double(step + 1) / config_.substeps;
    for (std::size_t i = 0; i < nc; ++i)
      coils_[i].series_emf =
          emf_start_[i] + (induced_emf_[i] - emf_start_[i]) * along + coils_[i].emf_offset;
    if (guard_) {
      substep(0.0), substep(0.0);
      guard_ = false;
    } else {
      substep(1.0);
    }
  }
  if (config_.rates) write_current_rates(access);
  // The current magnetic_forces makes the coil's pull from, for the rigid
  // body's step the next advance spans (coils_from_current).
  for (Coil& c : coils_) c.force_current = c.current;
  write_outputs(access);
  if (books_on_) book_light(access, dt);  // as the substeps' heat it is taken from
}

void ElectricityResolver::book_light(const WorldView& view, double dt) {
  // A lamp's power is the product light_from_electricity sends the light
  // resolver (the current and voltage just written), over this advance: the
  // light resolver books the same numbers, so the transfer's two sides agree
  // to rounding. Its visible share leaves the heat the substeps booked.
  if (!efficacy_id_) efficacy_id_ = view.properties().find(kLampEfficacy);
  if (!efficacy_id_) return;
  const auto efficacy = view.column<double>(*efficacy_id_);
  const auto current = current_id_.column<double>(view);
  const auto voltage = voltage_id_.column<double>(view);
  double light = 0;
  for (std::uint32_t s : efficacy.members()) {
    lamps_seen_ = true;
    const double p = current.value_or(s, 0.0) * voltage.value_or(s, 0.0);
    if (p > 0 && efficacy[s] > 0) light += efficacy[s] / kLumensPerLightWatt * p * dt;
  }
  books_.light += light;
  books_.heat -= light;
}

void ElectricityResolver::solve(const WorldView& view, std::span<const double> e,
                                std::span<double> potential, std::span<double> current) const {
  try {
    solver_.solve(e, potential, current);
  } catch (const NonFiniteSolution& failure) {
    // Only sources beyond any circuit's reach get here (the values a scene
    // sets are bounded; an induced EMF is not): name the circuit's parts
    // and its largest source, and point at that source's object.
    const PropertyStore& store = view.store();
    const auto component = solver_.component_of_node();
    std::string names;
    std::size_t count = 0;
    double largest = -1;
    ObjectId source;
    for (const Part& p : parts_) {
      if (component[p.node[0]] != failure.component) continue;
      if (++count <= 6)
        names +=
            std::string(names.empty() ? "'" : ", '") + store.describe(store.id_at(p.slot)) + "'";
      if (p.element >= 0 &&
          (p.kind == PartKind::Battery || p.kind == PartKind::Coil ||
           p.kind == PartKind::Capacitor) &&
          std::size_t(p.element) < e.size() && std::abs(e[std::size_t(p.element)]) > largest)
        largest = std::abs(e[std::size_t(p.element)]), source = store.id_at(p.slot);
    }
    if (count > 6) names += " and " + std::to_string(count - 6) + " more parts";
    throw InputError(
        ErrorLocation{"", 0, source.is_null() ? std::string() : store.describe(source)},
        "the circuit of " + names + " has no finite solution: its currents overflow a double" +
            (source.is_null() ? std::string()
                              : " (its largest source, '" + store.describe(source) + "', drives " +
                                    std::to_string(largest) + " V)") +
            "; see docs/electricity.md \"Values\"");
  }
}

void ElectricityResolver::Books::begin(const std::vector<Coil>& coils,
                                       const std::vector<Capacitor>& capacitors) {
  v_l0.resize(coils.size()), coil_current0.resize(coils.size());
  for (std::size_t i = 0; i < coils.size(); ++i)
    v_l0[i] = coils[i].v_l, coil_current0[i] = coils[i].current;
  charge0.resize(capacitors.size()), cap_current0.resize(capacitors.size());
  for (std::size_t j = 0; j < capacitors.size(); ++j)
    charge0[j] = capacitors[j].charge, cap_current0[j] = capacitors[j].current;
}

void ElectricityResolver::book_substep(double trap, double hs) {
  // Energy of one substep of length hs, from the element laws and the
  // integrator's own values. For the trapezoidal rule every product is of
  // the substep's mean current and mean voltage: then the coil's share is
  // exactly the change of 1/2 L I^2 (v_L' + v_L = 2L/h (I' - I)), the
  // capacitor's exactly that of q^2/2C, and by Tellegen's theorem (applied to
  // the mean of two solutions of the same network) battery work = heat +
  // stored change - EMF work, to rounding. A guard half-step (backward
  // Euler) uses the end values; its products exceed the stored change by
  // 1/2 L dI^2 and dq^2/2C, which is booked as "switching" (the numerical
  // damping of the guard, and the field of a coil whose loop opened: the
  // spark). The EMF over a trapezoidal substep is the mean of the one in
  // force at its start (kept in the history v_L) and the one now.
  const std::size_t nb = batteries_.size(), nc = coils_.size();
  auto mean = [&](double a0, double a1) { return trap > 0 ? 0.5 * (a0 + a1) : a1; };
  const auto& p = potential_;
  for (std::size_t k = 0; k < nb; ++k) {
    const double i = mean(books_.current0[k], branch_current_[k]);
    books_.battery += battery_emf_[k] * i * hs;
    books_.heat += network_.branches[k].z * i * i * hs;
  }
  for (std::size_t n = 0; n < nc; ++n) {
    const Coil& c = coils_[n];
    const double i = mean(books_.coil_current0[n], c.current);
    const double r = network_.branches[nb + n].z - 2 * c.inductance / h_;
    const double v_l = mean(books_.v_l0[n], c.v_l);
    books_.heat += r * i * i * hs;
    const double emf = mean(books_.emf0.size() > n ? books_.emf0[n] : c.series_emf, c.series_emf);
    books_.emf_work += emf * i * hs;
    // A coil whose loop opened at this advance's start passes no current,
    // but the rigid body's kick at the step's start was made from the
    // current before the opening, and its work along the mean velocity is
    // half this step's (the circuit's books pair each kick's work with the
    // two steps around it: docs/energy.md "Session 20"). Over a trapezoidal
    // step the current would have gone from that current to 0: the EMF's
    // work on the parts with the mean of the two, taken from the field the
    // opening released (switching), not left as the coupling's mismatch
    // (docs/magnetism.md "An opened loop").
    if (!branch_on_loop_[nb + n] && c.force_current != 0) {
      const double pulled = 0.5 * c.force_current;
      books_.emf_work += emf * pulled * hs;
      books_.switching += emf * pulled * hs;
    }
    const double i0 = books_.coil_current0[n];
    books_.switching += v_l * i * hs - 0.5 * c.inductance * (c.current * c.current - i0 * i0);
  }
  // Coils that share flux store M I_a I_b besides their own 1/2 L I^2: the
  // mutual parts of their inductive voltages, summed over both coils, give
  // exactly M d(I_a I_b) over a trapezoidal substep (M held over the
  // advance), and that plus M dI_a dI_b over a guard half-step. The change
  // is the store's, not switching.
  for (const Mutual& m : mutual_) {
    if (m.a >= nc || m.b >= nc) continue;
    books_.switching -= m.m * (coils_[m.a].current * coils_[m.b].current -
                               books_.coil_current0[m.a] * books_.coil_current0[m.b]);
  }
  for (std::size_t n = 0; n < capacitors_.size(); ++n) {
    const Capacitor& c = capacitors_[n];
    const double i = mean(books_.cap_current0[n], c.current);
    const double r = network_.branches[nb + nc + n].z - h_ / (2 * c.capacitance);
    const double q0 = books_.charge0[n];
    books_.heat += r * i * i * hs;
    books_.switching += mean(q0, c.charge) / c.capacitance * i * hs -
                        (c.charge * c.charge - q0 * q0) / (2 * c.capacitance);
  }
  // The conductances on loops (a bridge carries nothing): the longest loop
  // of a substep in a large network, so its two cases are written out and the
  // sum kept in a register; same operations in the same order as mean().
  {
    const double* p1 = p.data();
    const double* p0 = books_.potential0.size() == p.size() ? books_.potential0.data() : nullptr;
    double heat = books_.heat;
    if (trap > 0) {
      for (const Conductance& g : loop_conductances_) {
        const double v = 0.5 * ((p0 ? p0[g.a] - p0[g.b] : 0.0) + (p1[g.a] - p1[g.b]));
        heat += g.g * v * v * hs;
      }
    } else {
      for (const Conductance& g : loop_conductances_) {
        const double v = p1[g.a] - p1[g.b];
        heat += g.g * v * v * hs;
      }
    }
    books_.heat = heat;
  }
  books_.emf0.resize(nc);
  for (std::size_t n = 0; n < nc; ++n) books_.emf0[n] = coils_[n].series_emf;
}

void ElectricityResolver::report_energy(const WorldView& view, EnergyReport& out) {
  if (!books_on_) {
    // A ledger asks for the first time: the books start now, from the state
    // between steps. A trapezoidal substep's EMF is the mean of the one in
    // force at its start and its own, so the next one starts from the
    // series EMF of the last solve, as when the books were kept all along.
    books_on_ = true;
    books_.emf0.resize(coils_.size());
    for (std::size_t n = 0; n < coils_.size(); ++n) books_.emf0[n] = coils_[n].series_emf;
  }
  if (h_ == 0) {
    // Not advanced yet, so nothing is built; but a scene (or a save) may
    // start with a charged capacitor or a coil carrying current, which the
    // first advance takes up from the properties. The stores open at that
    // level, read the way the network will read it, or the ledger would see
    // the energy appear from nothing at the first step.
    const auto emf = view.column<double>(prop::kEmf);
    const auto inductance = view.column<double>(prop::kInductance);
    const auto capacitance = view.column<double>(prop::kCapacitance);
    const auto wire_from = view.column<ObjectId>(prop::kWireFrom);
    const auto wire_to = view.column<ObjectId>(prop::kWireTo);
    const auto current = current_id_.column<double>(view);
    const auto charge = charge_id_.column<double>(view);
    auto part = [&](std::uint32_t s) {
      return !emf.has(s) && !wire_from.has(s) && !wire_to.has(s);
    };
    double fields = 0, charges = 0;
    for (std::uint32_t s : inductance.members())
      if (part(s)) {
        const double i = current.value_or(s, 0.0);
        fields += 0.5 * inductance[s] * i * i;
      }
    for (std::uint32_t s : capacitance.members())
      if (part(s) && !inductance.has(s) && capacitance[s] >= kMinCapacitance) {
        const double q = charge.value_or(s, 0.0);
        charges += q * q / (2 * capacitance[s]);
      }
    out.store("coil fields (1/2 L I^2)", fields);
    out.store("capacitors (q^2 / 2C)", charges);
    return;
  }
  // The ledger books a non-finite figure as 0 J: say so instead (a power that
  // overflowed; the bounded circuit values keep this from any scene's values).
  for (const auto& [what, j] : {std::pair{"battery work", books_.battery},
                                {"heat", books_.heat},
                                {"switching", books_.switching},
                                {"the EMF's work", books_.emf_work}})
    if (!std::isfinite(j))
      throw std::runtime_error(std::string("electricity: the energy books overflowed: ") + what +
                               " is " + std::to_string(j) +
                               " J (a circuit's power beyond a double)");
  out.source("battery work", std::exchange(books_.battery, 0.0));
  out.sink("heat (I^2 R)", std::exchange(books_.heat, 0.0));
  out.sink("switching (guard steps, opened coils)", std::exchange(books_.switching, 0.0));
  // Induction's EMF works on the circuits with the energy the magnetic
  // forces take from (or give to) the moving parts: a transfer.
  out.transfer("magnetism", std::exchange(books_.emf_work, 0.0));
  // The lamps' visible light, given to the light resolver.
  if (lamps_seen_) out.transfer("light", -std::exchange(books_.light, 0.0));
  double fields = 0, charges = 0;
  for (const Coil& c : coils_) fields += 0.5 * c.inductance * c.current * c.current;
  for (const Capacitor& c : capacitors_) charges += c.charge * c.charge / (2 * c.capacitance);
  out.store("coil fields (1/2 L I^2)", fields);
  if (coils_.size() >= 2) {  // every report while coils could share flux
    double shared = 0;
    for (const Mutual& m : mutual_)
      if (m.a < coils_.size() && m.b < coils_.size())
        shared += m.m * coils_[m.a].current * coils_[m.b].current;
    out.store("coils' shared field (M I_a I_b)", shared);
  }
  out.store("capacitors (q^2 / 2C)", charges);
}

void ElectricityResolver::set_induced_emf(ObjectId coil, double emf, double step_mean) {
  induced_queue_.push_back({coil, emf, step_mean});
}

void ElectricityResolver::set_mutual_inductance(ObjectId a, ObjectId b, double henries) {
  mutual_queue_.emplace_back(a, b, henries);
}
double ElectricityResolver::mutual_inductance(ObjectId a, ObjectId b) const {
  for (const Mutual& m : mutual_)
    if (m.a < coils_.size() && m.b < coils_.size() &&
        ((coils_[m.a].slot == a.index && coils_[m.b].slot == b.index) ||
         (coils_[m.a].slot == b.index && coils_[m.b].slot == a.index)))
      return m.m;
  return 0.0;
}
void ElectricityResolver::take_mutual_inductances(const WorldView& view) {
  mutual_.clear();
  if (mutual_queue_.empty()) return;
  const PropertyStore& store = view.store();
  std::vector<std::int32_t> coil_of_slot(store.slot_count(), -1);
  for (std::size_t i = 0; i < coils_.size(); ++i) coil_of_slot[coils_[i].slot] = std::int32_t(i);
  auto coil = [&](ObjectId id) -> std::int32_t {
    return store.alive(id) && id.index < coil_of_slot.size() ? coil_of_slot[id.index] : -1;
  };
  for (const auto& [a, b, m] : mutual_queue_) {
    const std::int32_t i = coil(a), j = coil(b);
    if (i < 0 || j < 0 || i == j || !std::isfinite(m) || m == 0) continue;
    // A coupling of 1 or more would make the inductance matrix indefinite.
    const double limit =
        0.99 * std::sqrt(coils_[std::size_t(i)].inductance * coils_[std::size_t(j)].inductance);
    const double held = std::clamp(m, -limit, limit);
    const auto lo = std::uint32_t(std::min(i, j)), hi = std::uint32_t(std::max(i, j));
    auto it = std::find_if(mutual_.begin(), mutual_.end(),
                           [&](const Mutual& x) { return x.a == lo && x.b == hi; });
    if (it != mutual_.end())
      it->m = held;  // the last command wins
    else
      mutual_.push_back({lo, hi, held});
  }
  mutual_queue_.clear();
}
double ElectricityResolver::induced_emf(ObjectId coil) const {
  for (std::size_t i = 0; i < coils_.size() && i < induced_emf_.size(); ++i)
    if (coils_[i].slot == coil.index) return induced_emf_[i];
  return 0.0;
}

void ElectricityResolver::take_induced_emfs(const WorldView& view) {
  induced_emf_.assign(coils_.size(), 0.0);
  induced_mean_.assign(coils_.size(), std::numeric_limits<double>::quiet_NaN());
  if (induced_queue_.empty()) return;
  // Slot -> coil, for this advance's commands (coils are few; commands one per coil).
  const PropertyStore& store = view.store();
  std::vector<std::int32_t> coil_of_slot(store.slot_count(), -1);
  for (std::size_t i = 0; i < coils_.size(); ++i) coil_of_slot[coils_[i].slot] = std::int32_t(i);
  for (const InducedCommand& cmd : induced_queue_) {
    const ObjectId id = cmd.coil;
    if (!store.alive(id) || id.index >= coil_of_slot.size() || !std::isfinite(cmd.emf)) continue;
    if (const std::int32_t i = coil_of_slot[id.index]; i >= 0)
      induced_emf_[std::size_t(i)] = cmd.emf, induced_mean_[std::size_t(i)] = cmd.step_mean;
  }
  induced_queue_.clear();
}

void ElectricityResolver::set_resistance(ObjectId part, double ohms) {
  resistance_queue_.emplace_back(part, ohms);
}

double ElectricityResolver::set_resistance_of(ObjectId part) const {
  auto it = resistance_override_.find(part.index);
  return it == resistance_override_.end() ? -1.0 : it->second;
}

void ElectricityResolver::take_resistance_commands(const WorldView& view) {
  if (resistance_queue_.empty() && resistance_override_.empty()) return;
  const PropertyStore& store = view.store();
  std::map<std::uint32_t, double> next;
  for (const auto& [id, ohms] : resistance_queue_)
    if (store.alive(id) && std::isfinite(ohms) && ohms >= 0) next[id.index] = ohms;
  resistance_queue_.clear();
  // Only a changed value changes the matrix; the same value again costs nothing.
  if (next != resistance_override_) resistance_override_ = std::move(next), dirty_ = true;
}

void ElectricityResolver::write_current_rates(ResolverAccess& access) {
  // The inductor's voltage over L is the integrator's own dI/dt at the end
  // of the advance (for the trapezoidal rule and backward Euler alike; 0 on
  // an opened coil, whose current is exactly 0, and on a coil without L).
  auto rate = current_rate_id_.writer<double>(access);
  rate_slots_.resize(coils_.size()), rate_values_.resize(coils_.size());
  for (std::size_t i = 0; i < coils_.size(); ++i) {
    const Coil& c = coils_[i];
    rate_slots_[i] = c.slot, rate_values_[i] = c.inductance > 0 ? c.v_l / c.inductance : 0.0;
  }
  rate.set(rate_slots_, rate_values_);
}

void ElectricityResolver::write_outputs(ResolverAccess& access) {
  auto current = current_id_.writer<double>(access);
  auto voltage = voltage_id_.writer<double>(access);
  auto powered = powered_id_.writer<std::uint8_t>(access);
  auto charge = charge_id_.writer<double>(access);
  const double threshold = config_.powered_threshold;
  const auto& p = potential_;

  // Conductance currents, and the current passing each node: half the sum of
  // |current| over the elements that meet there (what flows in flows out).
  std::vector<double>& through = through_;
  std::vector<double>& g_current = g_current_;
  through.assign(network_.node_count, 0.0);
  g_current.resize(network_.conductances.size());
  const std::vector<std::uint8_t>& reports = node_reports_through_;
  for (std::size_t i = 0; i < network_.conductances.size(); ++i) {
    const Conductance& g = network_.conductances[i];
    g_current[i] = conductance_on_loop_[i] ? g.g * (p[g.a] - p[g.b]) : 0.0;
    if (reports[g.a]) through[g.a] += std::abs(g_current[i]) / 2;
    if (reports[g.b]) through[g.b] += std::abs(g_current[i]) / 2;
  }
  for (std::size_t k = 0; k < network_.branches.size(); ++k) {
    const TheveninBranch& br = network_.branches[k];
    if (reports[br.a]) through[br.a] += std::abs(branch_current_[k]) / 2;
    if (reports[br.b]) through[br.b] += std::abs(branch_current_[k]) / 2;
  }

  // The three columns are filled here in the order of output_slots_ (the
  // parts, the wires, the stale slots) and written in one call each.
  const std::size_t np = parts_.size(), nw = wires_.size();
  if (output_build_ != network_builds_) {
    output_slots_.clear();
    for (const Part& part : parts_) output_slots_.push_back(part.slot);
    for (const Wire& w : wires_) output_slots_.push_back(w.slot);
    output_slots_.insert(output_slots_.end(), stale_outputs_.begin(), stale_outputs_.end());
    output_build_ = network_builds_;
  }
  out_current_.resize(output_slots_.size()), out_voltage_.resize(output_slots_.size());
  out_powered_.resize(output_slots_.size());
  auto publish = [&](std::size_t at, double i, double v) {
    out_current_[at] = i;
    out_voltage_[at] = v;
    out_powered_[at] = std::abs(i) > threshold ? 1 : 0;
  };
  const PropertyStore& store = access.store();
  if (reported_cache_.size() != parts_.size()) {
    reported_cache_.assign(parts_.size(), 0);
    reported_cache_id_.assign(parts_.size(), ObjectId{});
  }
  for (std::size_t idx = 0; idx < parts_.size(); ++idx) {
    const Part& part = parts_[idx];
    const double v0 = p[part.node[0]], v1 = p[part.node[1]];
    double i = 0;
    switch (part.kind) {
      case PartKind::Node:
        publish(idx, through[part.node[0]], v0);
        continue;
      case PartKind::Battery:
        i = branch_current_[std::size_t(part.element)];
        publish(idx, i, v1 - v0);
        break;
      case PartKind::Coil:
      case PartKind::Capacitor:
        i = part.element < 0 ? 0.0 : branch_current_[std::size_t(part.element)];
        publish(idx, i, v0 - v1);
        break;
      case PartKind::Switch:
      case PartKind::Resistor:
        i = part.element < 0 ? 0.0 : g_current[std::size_t(part.element)];
        publish(idx, i, v0 - v1);
        break;
    }
    // Events when an element joins or leaves a closed loop.
    const ObjectId id = store.id_at(part.slot);
    std::uint8_t& cached = reported_cache_[idx];
    if (cached == 0 || reported_cache_id_[idx] != id)
      reported_cache_id_[idx] = id, cached = reported_closed_[id] ? 2 : 1;
    if ((cached == 2) != element_closed_[idx]) {
      bool& reported = reported_closed_[id];
      reported = element_closed_[idx];
      cached = reported ? 2 : 1;
      Event ev{.type = reported ? event::kCircuitClosed : event::kCircuitOpened,
               .a = id,
               .values = {{"current", i}}};
      if (part.kind == PartKind::Coil && !reported)
        ev.values.push_back(
            {"energy", coils_[std::size_t(part.element) - batteries_.size()].released});
      access.emit(std::move(ev));
    }
  }
  for (const Capacitor& c : capacitors_) charge.set(c.slot, c.charge);
  for (std::size_t wi = 0; wi < nw; ++wi) {
    const Wire& w = wires_[wi];
    if (w.conductance < 0) {
      publish(np + wi, 0.0, 0.0);
      continue;
    }
    const Conductance& g = network_.conductances[std::size_t(w.conductance)];
    publish(np + wi, g_current[std::size_t(w.conductance)], p[g.a] - p[g.b]);
  }
  for (std::size_t k = np + nw; k < output_slots_.size(); ++k) publish(k, 0.0, 0.0);
  current.set(output_slots_, out_current_);
  voltage.set(output_slots_, out_voltage_);
  powered.set(output_slots_, out_powered_);
}

void register_electricity_resolver(PluginRegistry& registry) {
  registry.add({
      .info = {.name = kResolverName,
               .kind = StageKind::Resolver,
               .reads = {prop::kConductive, prop::kEmf, prop::kInternalResistance,
                         prop::kInductance, prop::kResistance, prop::kContactResistance,
                         prop::kWireFrom, prop::kWireTo, prop::kWireFromTerminal,
                         prop::kWireToTerminal, prop::kCurrent, prop::kCapacitance, prop::kCharge,
                         prop::kSwitchClosed},
               .writes = {prop::kCurrent, prop::kVoltage, prop::kPowered, prop::kCurrentRate,
                          prop::kCharge},
               // Without a battery, a coil (which may hold a current) or a
               // capacitor (a charge) no current can flow: bars that merely
               // conduct need no solver.
               .needs = {prop::kEmf, prop::kInductance, prop::kCapacitance},
               .doc =
                   "circuits with coils and capacitors: modified nodal analysis over parts, wires "
                   "and contacts, trapezoidal in time"},
      .properties = electricity_property_defs(),
      .create =
          [](PluginContext& ctx) {
            return std::make_unique<ElectricityResolver>(ElectricityConfig::from(ctx.settings()));
          },
  });
}

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------

namespace {
// Version 2 (session 20): each coil's emf_offset.
constexpr std::uint32_t kStateVersion = 2;
// Saved as raw bytes: every byte a field.
struct SavedContact {
  ObjectId a, b;
  std::int64_t terminal_a, terminal_b;
};
struct SavedClosed {
  ObjectId id;
  std::uint64_t closed;
};
}  // namespace

bool ElectricityResolver::save_state(StateWriter& out) const {
  out.put(kStateVersion);
  std::vector<SavedContact> contacts;
  for (const auto& [key, c] : contacts_)
    contacts.push_back({key.first, key.second, c.terminal_a, c.terminal_b});
  out.put_vector(contacts);
  std::vector<SavedClosed> closed;
  for (const auto& [id, on] : reported_closed_) closed.push_back({id, on ? 1u : 0u});
  // reported_closed_ is a hash map: its order depends on its history, and
  // equal states must save equal bytes (they are hashed), so sort by id.
  std::sort(closed.begin(), closed.end(),
            [](const SavedClosed& a, const SavedClosed& b) { return a.id < b.id; });
  out.put_vector(closed);
  // Restored and not advanced yet: the history is still the saved one.
  const SavedHistory now{guard_, network_, batteries_, battery_emf_, coils_, capacitors_};
  const SavedHistory& h = restored_ ? *restored_ : now;
  out.put<std::uint8_t>(h.guard);
  out.put<std::uint32_t>(h.network.node_count);
  out.put_vector(h.network.conductances);
  out.put_vector(h.network.branches);
  out.put_vector(h.batteries);
  out.put_vector(h.battery_emf);
  out.put<std::uint64_t>(h.coils.size());
  for (const Coil& c : h.coils) {
    out.put<std::uint64_t>(c.slot);
    out.put(c.current), out.put(c.v_l), out.put(c.series_emf), out.put(c.emf_offset);
  }
  out.put<std::uint64_t>(h.capacitors.size());
  for (const Capacitor& c : h.capacitors) {
    out.put<std::uint64_t>(c.slot);
    out.put(c.charge), out.put(c.current);
  }
  return true;
}

void ElectricityResolver::restore_state(StateReader& in) {
  if (const auto v = in.get<std::uint32_t>(); v != kStateVersion)
    throw InputError("the saved state of stage '" + in.stage() + "' is of version " +
                     std::to_string(v) + ", this build reads " + std::to_string(kStateVersion));
  auto damaged = [&](const std::string& what) {
    throw InputError("the saved state of stage '" + in.stage() + "' is damaged: " + what);
  };
  // Everything is read and checked before anything changes. A contact's
  // terminals index its parts' two nodes when the network is built, and
  // connect() keeps every pair in (low, high) order: a file can hold neither
  // a terminal other than 0 or 1 nor a pair out of order.
  const auto contacts = in.get_vector<SavedContact>();
  for (const SavedContact& c : contacts)
    if (c.terminal_a < 0 || c.terminal_a > 1 || c.terminal_b < 0 || c.terminal_b > 1 ||
        !(c.a < c.b))
      damaged("a contact names terminal " + std::to_string(c.terminal_a) + " and " +
              std::to_string(c.terminal_b) + " of objects " + std::to_string(c.a.index) + " and " +
              std::to_string(c.b.index) + " (terminals are 0 and 1, in order)");
  const auto closed = in.get_vector<SavedClosed>();
  for (const SavedClosed& c : closed)
    if (c.closed > 1) damaged("a switch's reported state is " + std::to_string(c.closed));
  contacts_.clear();
  for (const SavedContact& c : contacts)
    contacts_[{c.a, c.b}] = Contact{int(c.terminal_a), int(c.terminal_b)};
  reported_closed_.clear();
  reported_cache_.clear();
  for (const SavedClosed& c : closed) reported_closed_[c.id] = c.closed != 0;
  auto saved = std::make_unique<SavedHistory>();
  saved->guard = in.get<std::uint8_t>() != 0;
  saved->network.node_count = in.get<std::uint32_t>();
  saved->network.conductances = in.get_vector<Conductance>();
  saved->network.branches = in.get_vector<TheveninBranch>();
  saved->batteries = in.get_vector<std::uint32_t>();
  saved->battery_emf = in.get_vector<double>();
  const auto coils = in.get<std::uint64_t>();
  for (std::uint64_t i = 0; i < coils && in.remaining() > 0; ++i) {
    Coil c{};
    c.slot = std::uint32_t(in.get<std::uint64_t>());
    c.current = in.get<double>(), c.v_l = in.get<double>(), c.series_emf = in.get<double>();
    c.emf_offset = in.get<double>();
    saved->coils.push_back(c);
  }
  const auto capacitors = in.get<std::uint64_t>();
  for (std::uint64_t i = 0; i < capacitors && in.remaining() > 0; ++i) {
    Capacitor c{};
    c.slot = std::uint32_t(in.get<std::uint64_t>());
    c.charge = in.get<double>(), c.current = in.get<double>();
    saved->capacitors.push_back(c);
  }
  if (saved->coils.size() != coils || saved->capacitors.size() != capacitors)
    throw InputError("the saved state of stage '" + in.stage() + "' is cut short");
  // The history is used only if the network matches (apply_restored), but a
  // value that is not finite would then reach every solve.
  auto finite = [](double v) { return std::isfinite(v); };
  bool ok = std::all_of(saved->battery_emf.begin(), saved->battery_emf.end(), finite);
  for (const Coil& c : saved->coils)
    ok = ok && finite(c.current) && finite(c.v_l) && finite(c.series_emf) && finite(c.emf_offset);
  for (const Capacitor& c : saved->capacitors) ok = ok && finite(c.charge) && finite(c.current);
  if (!ok) damaged("a battery's EMF, a coil's or a capacitor's state is not a finite number");
  restored_ = std::move(saved);
}

void ElectricityResolver::apply_restored() {
  // build_network after a restore starts from nothing, as after a network
  // change. If the network is the one the saved history was built for, the
  // uninterrupted resolver kept its history (build_network's `same`): so do
  // we. Otherwise its history was dropped too, and the fresh build is right.
  const std::unique_ptr<SavedHistory> saved = std::move(restored_);
  auto same_slots = [](const auto& a, const auto& b) {
    return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                      [](const auto& x, const auto& y) { return x.slot == y.slot; });
  };
  if (!(saved->network == network_) || saved->batteries != batteries_ ||
      !same_slots(saved->coils, coils_) || !same_slots(saved->capacitors, capacitors_) ||
      saved->battery_emf.size() != battery_emf_.size())
    return;
  guard_ = saved->guard;
  battery_emf_ = saved->battery_emf;
  for (std::size_t i = 0; i < coils_.size(); ++i)
    coils_[i].current = saved->coils[i].current, coils_[i].v_l = saved->coils[i].v_l,
    coils_[i].series_emf = saved->coils[i].series_emf,
    coils_[i].emf_offset = saved->coils[i].emf_offset;
  for (std::size_t i = 0; i < capacitors_.size(); ++i)
    capacitors_[i].charge = saved->capacitors[i].charge,
    capacitors_[i].current = saved->capacitors[i].current;
}

}  // namespace alloy::electricity
