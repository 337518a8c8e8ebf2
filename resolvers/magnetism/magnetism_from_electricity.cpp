#include "resolvers/magnetism/magnetism_from_electricity.hpp"

#include "resolvers/magnetism/magnet_parts.hpp"

namespace alloy::magnetism {

void MagnetismFromElectricity::apply(const WorldView& world) {
  const auto magnet = magnet_.column<EnumValue>(world);
  const auto current = current_.column<double>(world);
  const PropertyStore& store = world.store();
  // Every step, not only on change: the resolver keeps the last command, but a
  // swapped-in resolver starts with none, and coils are few.
  for (std::uint32_t slot : magnet.members()) {
    if (MagnetKind(magnet[slot].index) != MagnetKind::Electromagnet) continue;
    target_.set_coil_current(store.id_at(slot), current.value_or(slot, 0.0));
  }
}

}  // namespace alloy::magnetism
