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

void register_light_plugins(PluginRegistry& registry) {
  registry.add({
      .info =
          {.name = kResolverName,
           .kind = StageKind::Resolver,
           .reads = {prop::kLuminousEfficacy},
           .writes = {prop::kLuminousFlux, prop::kRadiantPower},
           .needs = {prop::kLuminousEfficacy, prop::kLightReceiver},
           .doc = "lamps radiate the electrical power they take: luminous flux = efficacy x power"},
      .properties = light_property_defs(),
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        ctx.settings().check_known(kResolverName, {});
        return std::make_unique<LightResolver>();
      },
  });
  registry.add({
      .info = {.name = kIlluminanceName,
               .kind = StageKind::Derived,
               .reads = {"position", "orientation", prop::kLuminousFlux, prop::kLightReceiver},
               .needs = {prop::kLightReceiver},
               .resolvers = {kResolverName},
               .doc =
                   "illuminance on every light receiver from every lamp (inverse square, cosine)"},
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        const PluginSettings& s = ctx.settings();
        s.check_known(kIlluminanceName, {"ambient"});
        const double ambient = s.number("ambient", 0.0);
        if (!(ambient >= 0) || !std::isfinite(ambient))
          throw InputError(s.where,
                           "illuminance: 'ambient' must be a finite illuminance >= 0 (lux)");
        return std::make_unique<IlluminanceSet>(ambient);
      },
  });
  registry.add({
      .info = {.name = kFromElectricityName,
               .kind = StageKind::Interaction,
               .reads = {prop::kLuminousEfficacy, "current", "voltage"},
               .needs = {prop::kLuminousEfficacy},
               // Active with electricity, which writes the currents it reads.
               .resolvers = {electricity::kResolverName},
               .target = kResolverName,
               .doc = "a lamp's electrical power V I is radiated as light at the next step"},
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        return std::make_unique<LightFromElectricity>(ctx.target<LightResolver>());
      },
  });
  registry.add({
      .info = {.name = kElectricityFromLightName,
               .kind = StageKind::Interaction,
               .reads = {prop::kDarkResistance, prop::kDarkIlluminance, prop::kPhotoGamma,
                         prop::kLitResistance},
               .needs = {prop::kDarkResistance},
               .derived = {kIlluminanceName},
               .target = electricity::kResolverName,
               .doc = "a photocell's resistance falls with the illuminance on it (R = R_dark "
                      "(E/E0)^-gamma)"},
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        return std::make_unique<ElectricityFromLight>(
            ctx.target<electricity::ElectricityResolver>(),
            ctx.dependency<IlluminanceSet>(kIlluminanceName));
      },
  });
}

}  // namespace alloy::light
