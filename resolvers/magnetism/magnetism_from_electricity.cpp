#include "resolvers/magnetism/magnetism_from_electricity.hpp"

#include <cmath>

#include "resolvers/magnetism/magnet_parts.hpp"

namespace alloy::magnetism {

void MagnetismFromElectricity::apply(const WorldView& world) {
  const auto magnet = magnet_.column<EnumValue>(world);
  const auto current = current_.column<double>(world);
  const PropertyStore& store = world.store();
  // With the magnetism resolver's rates the current goes with its rate, when
  // the electricity publishes one (its own setting `rates`).
  if (target_.rates()) {
    if (const auto id = world.properties().find(prop::kCurrentRate)) {
      const auto rate = world.column<double>(*id);
      for (std::uint32_t slot : magnet.members()) {
        if (MagnetKind(magnet[slot].index) != MagnetKind::Electromagnet) continue;
        target_.set_coil_current(store.id_at(slot), current.value_or(slot, 0.0),
                                 rate.value_or(slot, 0.0));
      }
      return;
    }
  }
  // The coupling's timing (docs/magnetism.md): the current read now (the
  // end of electricity's last advance, t) becomes the coil's pole strength
  // at the end of magnetism's next advance (t + dt), and the force of that
  // pole strength is the rigid body's kick at t + dt, held over its step
  // from t + dt to t + 2 dt. Semi-implicit Euler kicks with the force at
  // the step's start (its positions are those of Stormer-Verlet, second
  // order, with the force of that instant), so when electricity publishes
  // its currents' rates (its setting `rates`) the command is the current
  // predicted one step on, I + dt dI/dt: the current at t + dt (electricity's
  // induction_order 2, the default). Order 1 leads by 1.5 steps, the step's
  // mean current: it matches each step's books term by term but puts the
  // kick half a step late, first order in the motion (docs/magnetism.md).
  // Without rates the force's current is one step old.
  if (const auto id = world.properties().find(prop::kCurrentRate)) {
    const auto rate = world.column<double>(*id);
    const double lead = (induction_order_ == 2 ? 1.0 : 1.5) * world.dt();
    for (std::uint32_t slot : magnet.members()) {
      if (MagnetKind(magnet[slot].index) != MagnetKind::Electromagnet) continue;
      const double i = current.value_or(slot, 0.0), di = rate.value_or(slot, 0.0);
      target_.set_coil_current(store.id_at(slot), std::isfinite(di) ? i + lead * di : i);
    }
    return;
  }
  // Every step, not only on change: the resolver keeps the last command, but a
  // swapped-in resolver starts with none, and coils are few.
  for (std::uint32_t slot : magnet.members()) {
    if (MagnetKind(magnet[slot].index) != MagnetKind::Electromagnet) continue;
    target_.set_coil_current(store.id_at(slot), current.value_or(slot, 0.0));
  }
}

}  // namespace alloy::magnetism
