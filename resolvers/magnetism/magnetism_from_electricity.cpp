#include "resolvers/magnetism/magnetism_from_electricity.hpp"

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
  // Every step, not only on change: the resolver keeps the last command, but a
  // swapped-in resolver starts with none, and coils are few.
  for (std::uint32_t slot : magnet.members()) {
    if (MagnetKind(magnet[slot].index) != MagnetKind::Electromagnet) continue;
    target_.set_coil_current(store.id_at(slot), current.value_or(slot, 0.0));
  }
}

}  // namespace alloy::magnetism
