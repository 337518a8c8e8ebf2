#include "resolvers/light/light_plugins.hpp"

#include <cmath>

#include "resolvers/electricity/electricity.hpp"
#include "resolvers/light/light_interactions.hpp"

namespace alloy::light {

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
