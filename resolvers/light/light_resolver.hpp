// The light resolver: lamps turn the electrical power they take into light
// (docs/light.md). It is the paper's own example of an interaction between
// two physics (electricity -> light): light_from_electricity reads each
// lamp's current and voltage after the electricity's advance and queues the
// power on this resolver with emit(); the next advance performs it.
//
// Lamps    objects carrying `luminous_efficacy` (lm per electrical W). The
//          kit's lamp is also an electrical resistor; the light resolver does
//          not care how the power was made.
// Writes   `luminous_flux` (lm) and `radiant_power` (W) on every lamp.
// Reads    luminous_efficacy.
// Needs    luminous_efficacy or light_receiver (a photocell alone still has
//          an illuminance: the ambient setting of the illuminance set).
// Energy   a lamp radiates what it takes: radiant_power is its electrical
//          power (light and heat radiation; the filament's conduction losses
//          are neglected). emitted_energy() is the energy radiated in the last
//          advance, J. Its visible share, efficacy / 683 lm/W (the luminous
//          efficiency), is the ledger's "light" (docs/energy.md): electricity
//          gives it (out of the lamp's I^2 R), this resolver receives it when
//          the power is queued, holds it until the advance that radiates it (a
//          store: the step's delay), and books it leaving the scene (a sink).
//
// State: none beyond properties. The queued power of the next advance is
// rebuilt by the interaction when a world is primed, so a rebuild, a swap or
// a restore loses nothing.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "runtime/plugin_registry.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"
#include "runtime/world.hpp"

namespace alloy::light {

/// Property names: a contract with the kit, the viewer and the interactions.
namespace prop {
/// Lamp: luminous flux per watt of electrical power, lm/W (marks a lamp).
inline constexpr const char* kLuminousEfficacy = "luminous_efficacy";
/// Lamp, written: luminous flux over the last advance, lm.
inline constexpr const char* kLuminousFlux = "luminous_flux";
/// Lamp, written: power radiated over the last advance, W.
inline constexpr const char* kRadiantPower = "radiant_power";
/// Receiver: true if the object measures the light falling on its face (+y of its frame).
inline constexpr const char* kLightReceiver = "light_receiver";
/// Photocell: resistance in the dark, Ohm (marks a photocell).
inline constexpr const char* kDarkResistance = "dark_resistance";
/// Photocell: illuminance up to which it stays at its dark resistance, lux.
inline constexpr const char* kDarkIlluminance = "dark_illuminance";
/// Photocell: the exponent of its law R = R_dark (E / E0)^-gamma.
inline constexpr const char* kPhotoGamma = "photo_gamma";
/// Photocell: the least resistance, in full light, Ohm.
inline constexpr const char* kLitResistance = "lit_resistance";
}  // namespace prop

/// Plugin names.
inline constexpr const char* kResolverName = "light";
inline constexpr const char* kIlluminanceName = "illuminance";
inline constexpr const char* kFromElectricityName = "light_from_electricity";
inline constexpr const char* kElectricityFromLightName = "electricity_from_light";

/// The property types light defines (lamps, receivers, photocells).
std::vector<PropertyDef> light_property_defs();

class LightResolver final : public Resolver {
 public:
  // --- interaction function: queued, performed in the next advance ------------
  /// Over the next advance, lamp `lamp` takes `watts` of electrical power and
  /// radiates it. The last command before an advance wins; a lamp with no
  /// command is dark. A command for an object that is not a lamp, or with a
  /// negative or non-finite value, does nothing.
  void emit(ObjectId lamp, double watts) { queue_.emplace_back(lamp, watts); }

  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  /// The "light" transfer (received), the light queued for the next advance
  /// (a store) and the light radiated (a sink), docs/energy.md.
  void report_energy(const WorldView& view, EnergyReport& out) override;

  // --- for an energy ledger, tests and tools -----------------------------------
  /// Energy all lamps radiated in the last advance, J (sum of radiant_power x dt).
  double emitted_energy() const { return emitted_energy_; }
  /// The same, summed over every advance of this instance, J (not saved: a
  /// restored world starts it at 0).
  double total_emitted_energy() const { return total_emitted_energy_; }
  /// Lamps lit (radiant_power > 0) in the last advance.
  std::size_t lit_count() const { return lit_count_; }

 private:
  std::vector<std::pair<ObjectId, double>> queue_;
  std::vector<double> power_;  // by slot, this advance's commands, W (-1: none)
  double emitted_energy_ = 0, total_emitted_energy_ = 0;
  // The books: visible light radiated since the last report, the queued
  // light's value at the last report, the dt of the last advance, J and s.
  double light_radiated_ = 0, light_queued_ = 0, last_dt_ = 0;
  bool reported_ = false;
  /// The visible light the queued commands carry over an advance of `dt`, J
  /// (the last command per lamp, as advance() takes them).
  double queued_light(const WorldView& view, double dt);
  std::size_t lit_count_ = 0;
  PropertyRef efficacy_{prop::kLuminousEfficacy}, flux_{prop::kLuminousFlux},
      radiant_{prop::kRadiantPower};
};

}  // namespace alloy::light
