// Scene builders shared by the magnetism tests: kit-sized bars (10 cm x 2 cm x
// 2 cm) of each magnetic kind, and a stand-in for the electricity resolver that
// publishes a `current` chosen by the test.
#pragma once

#include <memory>
#include <string>

#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "resolvers/magnetism/magnetism_plugins.hpp"
#include "resolvers/magnetism/magnetism_resolver.hpp"
#include "runtime/world.hpp"

namespace alloy::magnetism::testing {

inline constexpr Vec3 kBarSize{0.1, 0.02, 0.02};

/// Publishes `current` on every object carrying it: the value of `next` at each advance.
class CurrentSource : public Resolver {
 public:
  void build(ResolverAccess&) override {}
  void advance(ResolverAccess& a, double) override {
    auto current = a.writer<double>(prop::kCurrent);
    for (std::uint32_t slot : current.members()) current.set(slot, next);
  }
  double next = 0;  ///< A
};

/// Registers the stand-in under the electricity resolver's name, "electricity",
/// with its definition of `current` (magnetism_from_electricity runs only when
/// a resolver of that name does).
inline void register_current_source(PluginRegistry& r) {
  r.add({.info = {.name = "electricity",
                  .kind = StageKind::Resolver,
                  .writes = {prop::kCurrent},
                  .needs = {prop::kCurrent}},
         .properties = {{.name = prop::kCurrent,
                         .kind = PropertyKind::Number,
                         .unit = "A",
                         .doc = "current through the element"}},
         .create = [](PluginContext&) { return std::make_unique<CurrentSource>(); }});
  // The real resolver's interactions (registered with the native plugins)
  // call connect() and set_induced_emf() on an ElectricityResolver; the
  // stand-in has neither.
  r.remove("electricity_from_collisions");
  r.remove("electricity_from_magnetism");
}

/// A bar on the play area at `at`, rotated by `angle` about z, of the given kind.
inline ObjectId add_bar(World& w, const std::string& name, MagnetKind kind, Vec3 at,
                        double angle = 0, Vec3 size = kBarSize) {
  const ObjectId id = w.create(name);
  const PropertyRegistry& reg = w.properties();
  w.set(id, prop::kPosition, at);
  w.set(id, prop::kOrientation, Quat::from_angle_z(angle));
  w.set(id, prop::kShape, *reg.enum_value(reg.id(prop::kShape), "box"));
  w.set(id, prop::kSize, size);
  w.set(id, prop::kMagnet, EnumValue{std::int32_t(kind)});
  return id;
}

inline ObjectId add_permanent(World& w, const std::string& name, Vec3 at, double angle, double q) {
  const ObjectId id = add_bar(w, name, MagnetKind::Permanent, at, angle);
  w.set(id, prop::kPoleStrength, q);
  return id;
}

inline ObjectId add_coil(World& w, const std::string& name, Vec3 at, double angle, double turns) {
  const ObjectId id = add_bar(w, name, MagnetKind::Electromagnet, at, angle);
  w.set(id, prop::kTurns, turns);
  return id;
}

inline ObjectId add_iron(World& w, const std::string& name, Vec3 at, double angle, double chi) {
  const ObjectId id = add_bar(w, name, MagnetKind::SoftIron, at, angle);
  w.set(id, prop::kSusceptibility, chi);
  return id;
}

inline CurrentSource& current_source_of(World& w) {
  return dynamic_cast<CurrentSource&>(*w.stage("electricity"));
}
inline MagneticForces& forces_of(World& w) {
  return dynamic_cast<MagneticForces&>(*w.stage(MagneticForces::kName));
}
inline MagnetismResolver& magnetism_of(World& w) {
  return dynamic_cast<MagnetismResolver&>(*w.stage(MagnetismResolver::kName));
}
inline double number(const World& w, ObjectId id, const char* property) {
  return std::get<double>(w.get(id, property));
}

}  // namespace alloy::magnetism::testing
