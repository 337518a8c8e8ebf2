#include "resolvers/light/light_interactions.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "resolvers/electricity/electricity.hpp"

namespace alloy::light {

double photocell_resistance(double e, double dark, double e0, double gamma, double lit) {
  if (!(e > e0)) return dark;  // also a NaN illuminance: dark
  return std::max(lit, dark * std::pow(e / e0, -gamma));
}

void LightFromElectricity::apply(const WorldView& world) {
  const auto efficacy = efficacy_.column<double>(world);
  const auto current = current_.column<double>(world);
  const auto voltage = voltage_.column<double>(world);
  const PropertyStore& store = world.store();
  for (std::uint32_t s : efficacy.members()) {
    // A lamp that is in no circuit (no current written) is dark. The product
    // is >= 0 for a resistor: its voltage is the drop along its current.
    const double p = current.value_or(s, 0.0) * voltage.value_or(s, 0.0);
    target_.emit(store.id_at(s), p > 0 ? p : 0.0);
  }
}

void ElectricityFromLight::apply(const WorldView& world) {
  const auto dark = dark_.column<double>(world);
  const auto e0 = e0_.column<double>(world);
  const auto gamma = gamma_.column<double>(world);
  const auto lit = lit_.column<double>(world);
  const PropertyStore& store = world.store();
  for (const IlluminanceSet::Receiver& r : set_.receivers()) {
    const std::uint32_t s = r.id.index;
    if (!dark.has(s)) continue;  // a receiver that is not a photocell
    const double rd = dark[s], rl = lit.value_or(s, kDefaultLitResistance);
    if (rl > rd)
      throw InputError(ErrorLocation{"", 0, store.describe(r.id)},
                       "photocell: lit_resistance (" + std::to_string(rl) +
                           " Ohm) must not exceed dark_resistance (" + std::to_string(rd) +
                           " Ohm)");
    target_.set_resistance(
        r.id, photocell_resistance(r.illuminance, rd, e0.value_or(s, kDefaultDarkIlluminance),
                                   gamma.value_or(s, kDefaultGamma), rl));
  }
}

}  // namespace alloy::light
