// The magnetism property types and how a magnetic part is read from them.
//
// An object is magnetic when it carries `magnet`. Its poles lie on its local x
// axis, symmetric about its position (the centre of mass). Which properties
// matter depends on the kind (docs/magnetism.md lists them with examples):
//
//   permanent      pole_strength (signed: > 0 puts north at the +x end)
//   electromagnet  turns, coil_factor (default from the shape), coil_time_constant;
//                  pole_strength is written by the magnetism resolver from the coil current
//   soft_iron      susceptibility, saturation_pole (default from iron's saturation);
//                  its poles are induced by the field, see magnetic_forces.hpp
//
// All kinds: pole_separation (default 0.85 x the part's length along x).
// Geometry (position, orientation, shape, size, radius, length) belongs to the
// rigid body; these names and meanings are the rigid body's.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "runtime/access.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/world.hpp"

namespace alloy::magnetism {

/// Property names, stable: the Lua kit exposes them.
namespace prop {
inline constexpr const char* kMagnet = "magnet";
inline constexpr const char* kPoleStrength = "pole_strength";
inline constexpr const char* kPoleSeparation = "pole_separation";
inline constexpr const char* kTurns = "turns";
inline constexpr const char* kCoilFactor = "coil_factor";
inline constexpr const char* kCoilTimeConstant = "coil_time_constant";
inline constexpr const char* kSusceptibility = "susceptibility";
inline constexpr const char* kSaturationPole = "saturation_pole";
// Read, owned by the rigid body.
inline constexpr const char* kPosition = "position";
inline constexpr const char* kOrientation = "orientation";
inline constexpr const char* kShape = "shape";
inline constexpr const char* kSize = "size";
inline constexpr const char* kRadius = "radius";
inline constexpr const char* kLength = "length";
// Read, owned by electricity.
inline constexpr const char* kCurrent = "current";
inline constexpr const char* kCurrentRate = "current_rate";
// Written by magnetism with rates = true.
inline constexpr const char* kPoleStrengthRate = "pole_strength_rate";
}  // namespace prop

/// Values of the `magnet` enum, in registration order.
enum class MagnetKind : std::int32_t { Permanent = 0, Electromagnet = 1, SoftIron = 2 };

/// The property types magnetism defines.
std::vector<PropertyDef> magnetism_property_defs();

/// Registers the geometry properties magnetism reads (position, orientation,
/// shape, size, radius, length) with the rigid body's definitions, but only
/// those not registered yet: the rigid body owns them, and magnetism must also
/// run in a registry without it (tests, a magnetism-only tool).
void ensure_geometry_properties(PropertyRegistry& registry);

/// The columns a magnetic part is read from, bound once per pass.
struct MagnetColumns {
  ColumnView<EnumValue> magnet;
  ColumnView<double> pole_strength, pole_separation, turns, coil_factor, coil_time_constant,
      susceptibility, saturation_pole;
  ColumnView<Vec3> position;
  ColumnView<Quat> orientation;
  ColumnView<EnumValue> shape;
  ColumnView<Vec3> size;
  ColumnView<double> radius, length;
  /// Indices of the shape enum's values, or -1 if the shape enum lacks them.
  int shape_box = -1, shape_sphere = -1, shape_capsule = -1;

  /// The property ids and shape enum indices behind the columns. They never
  /// change once registered, so a stage resolves them once and binds from
  /// them in every step (a lookup by name per column was 2 % of the motor's step).
  struct Ids {
    PropertyId magnet, pole_strength, pole_separation, turns, coil_factor, coil_time_constant,
        susceptibility, saturation_pole, position, orientation, shape, size, radius, length;
    int shape_box = -1, shape_sphere = -1, shape_capsule = -1;
    static Ids resolve(const WorldView& world);
  };

  static MagnetColumns bind(const WorldView& world, const Ids& ids);
  /// Looks the ids up by name: for tools and tests, not for a step.
  static MagnetColumns bind(const WorldView& world) { return bind(world, Ids::resolve(world)); }
  MagnetKind kind(std::uint32_t slot) const { return MagnetKind(magnet[slot].index); }
};

/// The bulk geometry of a part, from its rigid-body shape.
struct PartBulk {
  double length = 0;         ///< extent along local x, m
  double cross_section = 0;  ///< area across x, m^2
  double volume = 0;         ///< m^3
  double aspect_ratio = 1;   ///< length / equivalent diameter (for demagnetisation)
};

/// The part's bulk geometry, or nullopt if it carries no usable shape.
std::optional<PartBulk> part_bulk(const MagnetColumns& c, std::uint32_t slot);

/// Distance between the part's two poles, m: `pole_separation` if carried,
/// else kMagneticLengthRatio times the shape's length; nullopt if neither.
std::optional<double> pole_separation(const MagnetColumns& c, std::uint32_t slot);

/// Pole strength per ampere-turn of an electromagnet, m: `coil_factor` if
/// carried, else cross-section / pole separation (an air-core solenoid's
/// moment N I A spread over its poles); nullopt if the geometry is missing.
std::optional<double> coil_factor(const MagnetColumns& c, std::uint32_t slot);

/// What the induction solve needs of a soft-iron part.
struct SoftIronModel {
  double gain = 0;        ///< induced pole strength per axial field, m^2
  double saturation = 0;  ///< A*m
};
std::optional<SoftIronModel> soft_iron_model(const MagnetColumns& c, std::uint32_t slot);

/// Why a magnetic part cannot be simulated ("" if it can): the message names
/// what is missing, for the scene author.
std::string check_part(const MagnetColumns& c, std::uint32_t slot);

}  // namespace alloy::magnetism
