// The `illuminance` derived set: for every light receiver, the illuminance
// from every lamp (docs/light.md, "Illuminance").
//
// A lamp is a point source radiating its luminous flux Phi evenly in all
// directions (a bulb is small next to the distances of a kit scene), so its
// intensity is Phi / 4 pi (cd). A receiver at distance r whose face's normal
// n makes the angle theta with the direction to the lamp gets
//
//     E = Phi cos(theta) / (4 pi r^2)    (lux; 0 when the lamp is behind the face)
//
// the inverse-square and cosine laws. The same law serves planar (2D) kit
// scenes and 3D ones: a planar scene's parts still sit in 3D space, and a
// point source spreads its light over a sphere, not a circle. Distances below
// kMinDistance are taken as kMinDistance (a bulb has a size). Nothing
// occludes: a part between a lamp and a receiver casts no shadow, and light
// is not reflected (out of scope, docs/light.md "Limits").
//
// Contract:
//   reads      position, orientation, luminous_flux, light_receiver
//   resolvers  light (the lamps' flux it publishes)
//   setting    ambient (lux, default 0): added to every receiver, lit face or not
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/math.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"

namespace alloy::light {

/// Distances below this are taken as this, m: a bulb's size.
inline constexpr double kMinDistance = 0.01;
inline constexpr double kPi = 3.14159265358979323846;

/// The law itself, m and lm in, lux out: the illuminance on a face at
/// `receiver` with unit normal `normal` from an isotropic point source of
/// `flux` at `source`.
double point_illuminance(double flux, Vec3 source, Vec3 receiver, Vec3 normal);

class IlluminanceSet final : public DerivedSet {
 public:
  explicit IlluminanceSet(double ambient = 0) : ambient_(ambient) {}
  void update(const WorldView& world) override;

  /// One receiver's illuminance as of the last update.
  struct Receiver {
    ObjectId id;
    double illuminance = 0;  ///< lux, every lamp plus ambient
  };
  /// One lamp's share on one receiver, lux.
  struct Share {
    ObjectId receiver, lamp;
    double illuminance = 0;
  };
  std::span<const Receiver> receivers() const { return receivers_; }
  /// Every (receiver, lamp) pair with a lit face, by receiver then lamp.
  std::span<const Share> shares() const { return shares_; }
  /// The receiver `id`'s illuminance, lux (0 if it is not a receiver).
  double illuminance(ObjectId id) const;
  /// Lamp `lamp`'s share on receiver `receiver`, lux (0 if none).
  double share(ObjectId receiver, ObjectId lamp) const;
  double ambient() const { return ambient_; }

 private:
  double ambient_;
  std::vector<Receiver> receivers_;
  std::vector<Share> shares_;
  PropertyRef position_{"position"}, orientation_{"orientation"}, flux_{"luminous_flux"},
      receiver_{"light_receiver"};
};

}  // namespace alloy::light
