// The two interactions between light and electricity (docs/light.md):
//
//   light_from_electricity   target light: each lamp's electrical power
//                            P = V I (its voltage drop along its current,
//                            times the current: I^2 R for a resistor) is
//                            queued with LightResolver::emit.
//   electricity_from_light   target electricity: each photocell's resistance
//                            from the illuminance on it (photocell_resistance
//                            below) is queued with
//                            ElectricityResolver::set_resistance.
//
// With both, light drives a circuit back: a lamp lighting a photocell in its
// own circuit is a loop through two physics, each leg a step late (the
// paper's one-step delay), which settles where the two laws agree.
//
// Both live here, beside the light resolver (electricity_from_light would
// belong to resolvers/electricity/ by the naming rule; it shares this file with
// its twin). They are built with light's plugins, which link electricity.
#pragma once

#include "resolvers/light/illuminance.hpp"
#include "resolvers/light/light_resolver.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"

namespace alloy::electricity {
class ElectricityResolver;
}

namespace alloy::light {

/// A photocell's law (a CdS light-dependent resistor): R = R_dark for E <=
/// E0, R_dark (E / E0)^-gamma above, never below `lit` (a real cell's
/// resistance levels off in bright light). Ohm; `e` in lux.
double photocell_resistance(double e, double dark, double e0, double gamma, double lit);

/// Defaults of a photocell that does not carry them (a GL5528-like CdS cell:
/// 1 MOhm dark, about 10 kOhm at 10 lux, gamma 0.7, 100 Ohm in sunlight).
inline constexpr double kDefaultGamma = 0.7;
inline constexpr double kDefaultDarkIlluminance =
    0.0139;  // lux: puts 10 kOhm at 10 lux with 1 MOhm dark
inline constexpr double kDefaultLitResistance = 100;  // Ohm

class LightFromElectricity final : public Interaction {
 public:
  explicit LightFromElectricity(LightResolver& target) : target_(target) {}
  void apply(const WorldView& world) override;

 private:
  LightResolver& target_;
  PropertyRef efficacy_{prop::kLuminousEfficacy}, current_{"current"}, voltage_{"voltage"};
};

class ElectricityFromLight final : public Interaction {
 public:
  ElectricityFromLight(electricity::ElectricityResolver& target, const IlluminanceSet& set)
      : target_(target), set_(set) {}
  void apply(const WorldView& world) override;

 private:
  electricity::ElectricityResolver& target_;
  const IlluminanceSet& set_;
  PropertyRef dark_{prop::kDarkResistance}, e0_{prop::kDarkIlluminance}, gamma_{prop::kPhotoGamma},
      lit_{prop::kLitResistance};
};

}  // namespace alloy::light
