// The (Electricity <- Magnetism) interaction: Faraday's law. Every step, for
// each electromagnet that is also a coil of a circuit (carries `inductance`),
// the flux linking it from every other magnetic part (permanent magnets,
// other electromagnets, magnetised iron: the poles of the `magnetic_forces`
// set) and its rate along the parts' present motion (flux_linkage.hpp); the
// EMF -dPhi/dt is queued on the electricity resolver, which adds it to the
// coil's branch in its next advance. With magnetism_from_electricity (the
// current makes the coil a magnet) and rigid_body_from_magnetism (the
// magnet's force moves the parts) it closes the loop of a motor and a
// generator: the work the coil's field does on the parts is the energy the
// EMF takes from the circuit (Lenz).
//
// Contract:
//   reads    the magnetic_forces derived set (its poles), magnet, turns,
//            coil_factor, pole_separation, inductance, position, orientation,
//            velocity, angular_velocity and the shape (for the defaults)
//   target   electricity (set_induced_emf, set_mutual_inductance)
//   needs    magnet
// The coil's own current is not a source here: its self-inductance is the
// circuit's `inductance`. Changes of other coils' currents (a transformer)
// enter as each pair's mutual inductance (flux_linkage.hpp), queued with
// set_mutual_inductance and solved implicitly by electricity.
#pragma once

#include <optional>
#include <vector>

#include "resolvers/magnetism/flux_linkage.hpp"
#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"

namespace alloy::electricity {
class ElectricityResolver;
}

namespace alloy::magnetism {

class ElectricityFromMagnetism : public Interaction {
 public:
  /// Plugin name.
  static constexpr const char* kName = "electricity_from_magnetism";

  ElectricityFromMagnetism(electricity::ElectricityResolver& target, const MagneticForces& forces)
      : target_(target), forces_(forces) {}
  void apply(const WorldView& world) override;

  /// One coil's flux linkage and rate as of the last apply.
  struct CoilFlux {
    ObjectId id;
    FluxLinkage linkage;
  };
  /// Every coil of the last apply (tests, tools).
  const std::vector<CoilFlux>& coils() const { return coils_; }
  /// The coil `id` as of the last apply, or nullptr.
  const CoilFlux* find(ObjectId id) const;
  /// A pair of coils and their mutual inductance, as queued in the last apply.
  struct CoilPair {
    ObjectId a, b;
    double mutual_inductance;  ///< H
  };
  const std::vector<CoilPair>& mutual_inductances() const { return mutuals_; }

 private:
  electricity::ElectricityResolver& target_;
  const MagneticForces& forces_;
  std::vector<CoilFlux> coils_;
  std::vector<CoilPair> mutuals_;
  std::vector<Vec3> pole_velocity_;
  std::vector<Pole> moved_poles_;  // the poles one step on (scratch)
  std::optional<MagnetColumns::Ids> ids_;
  PropertyRef inductance_{"inductance"}, velocity_{"velocity"}, spin_{"angular_velocity"};
};

/// Registers electricity_from_magnetism (after the magnetism and electricity
/// plugins, whose set and resolver it joins).
void register_electricity_from_magnetism(PluginRegistry& registry);

}  // namespace alloy::magnetism
