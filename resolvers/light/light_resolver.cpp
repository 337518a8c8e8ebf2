#include "resolvers/light/light_resolver.hpp"

#include <cmath>
#include <utility>

#include "resolvers/electricity/electricity.hpp"

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
  double radiated = 0, light = 0;
  lit_count_ = 0;
  for (std::uint32_t s : efficacy.members()) {
    const double p = power_[s] > 0 ? power_[s] : 0.0;  // no command: dark
    flux.set(s, efficacy[s] * p);
    radiant.set(s, p);
    radiated += p * dt;
    if (efficacy[s] > 0) light += efficacy[s] / electricity::kLumensPerLightWatt * p * dt;
    lit_count_ += p > 0;
  }
  emitted_energy_ = radiated;
  total_emitted_energy_ += radiated;
  light_radiated_ += light;
  last_dt_ = dt;
}

double LightResolver::queued_light(const WorldView& view, double dt) {
  const auto efficacy = efficacy_.column<double>(view);
  const PropertyStore& store = view.store();
  std::vector<double>& power = power_;  // advance() fills it afresh
  power.assign(store.slot_count(), 0.0);
  for (const auto& [id, watts] : queue_)
    if (store.alive(id) && efficacy.has(id.index) && std::isfinite(watts) && watts >= 0)
      power[id.index] = watts;
  double light = 0;
  for (std::uint32_t s : efficacy.members())
    if (power[s] > 0 && efficacy[s] > 0)
      light += efficacy[s] / electricity::kLumensPerLightWatt * power[s] * dt;
  return light;
}

void LightResolver::report_energy(const WorldView& view, EnergyReport& out) {
  // light_from_electricity queued this step's power after electricity's
  // advance, which booked its light in the same step: received now, at the
  // dt of the advance that will radiate it (the last one's; the world's
  // before the first), held until then. What was received: what the
  // advances since the last report radiated, plus the change of what waits.
  const double queued = queued_light(view, last_dt_ > 0 ? last_dt_ : view.dt());
  if (!reported_) {
    // The store opens at its level, and what was radiated before the ledger
    // opened is not booked (electricity books the light it gives only from
    // then on, as its heat).
    light_queued_ = queued, light_radiated_ = 0, reported_ = true;
  }
  out.transfer("light", light_radiated_ + queued - std::exchange(light_queued_, queued));
  out.store("light queued for the next step", queued);
  out.sink("light leaving the scene", std::exchange(light_radiated_, 0.0));
}

}  // namespace alloy::light
