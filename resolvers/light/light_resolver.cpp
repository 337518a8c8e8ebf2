#include "resolvers/light/light_resolver.hpp"

#include <cmath>

namespace alloy::light {

namespace {
PropertyDef number(const char* name, const char* unit, const char* doc,
                   std::optional<double> min = {}, bool exclusive = false) {
  return {.name = name,
          .kind = PropertyKind::Number,
          .unit = unit,
          .doc = doc,
          .min = min,
          .min_exclusive = exclusive};
}
}  // namespace

std::vector<PropertyDef> light_property_defs() {
  return {
      number(prop::kLuminousEfficacy, "lm/W",
             "lamp: luminous flux per watt of electrical power (a small tungsten bulb: about 10)",
             0.0),
      number(prop::kLuminousFlux, "lm", "lamp, written by light: luminous flux over the last step"),
      number(prop::kRadiantPower, "W", "lamp, written by light: power radiated over the last step"),
      {.name = prop::kLightReceiver,
       .kind = PropertyKind::Bool,
       .doc = "measures the illuminance on its face (the +y side of its frame)"},
      number(prop::kDarkResistance, "Ohm", "photocell: resistance in the dark", 0.0, true),
      number(prop::kDarkIlluminance, "lx",
             "photocell: illuminance up to which it keeps its dark resistance (E0)", 0.0, true),
      number(prop::kPhotoGamma, "", "photocell: exponent gamma of R = R_dark (E / E0)^-gamma", 0.0),
      number(prop::kLitResistance, "Ohm", "photocell: least resistance, in full light", 0.0, true),
  };
}

void LightResolver::build(ResolverAccess& access) {
  // Every lamp carries its outputs from the start, so that advance() only
  // changes values (a new membership would rebuild every resolver).
  auto flux = flux_.writer<double>(access);
  auto radiant = radiant_.writer<double>(access);
  for (std::uint32_t s : efficacy_.column<double>(access).members()) {
    if (!flux.has(s)) flux.set(s, 0.0);
    if (!radiant.has(s)) radiant.set(s, 0.0);
  }
}

void LightResolver::advance(ResolverAccess& access, double dt) {
  const auto efficacy = efficacy_.column<double>(access);
  const PropertyStore& store = access.store();
  power_.assign(store.slot_count(), -1.0);
  for (const auto& [id, watts] : queue_)
    if (store.alive(id) && efficacy.has(id.index) && std::isfinite(watts) && watts >= 0)
      power_[id.index] = watts;
  queue_.clear();

  auto flux = flux_.writer<double>(access);
  auto radiant = radiant_.writer<double>(access);
  double radiated = 0;
  lit_count_ = 0;
  for (std::uint32_t s : efficacy.members()) {
    const double p = power_[s] > 0 ? power_[s] : 0.0;  // no command: dark
    flux.set(s, efficacy[s] * p);
    radiant.set(s, p);
    radiated += p * dt;
    lit_count_ += p > 0;
  }
  emitted_energy_ = radiated;
  total_emitted_energy_ += radiated;
}

}  // namespace alloy::light
