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
//                  its poles are induced by the field along the field (isotropic
//                  iron, demagnetised by its shape), see magnetic_forces.hpp
//   electromagnet with susceptibility: the coil has a soft-iron core (a rod
//                  along x of diameter core_diameter), which the field of the
//                  other parts magnetises along the coil's axis
//
// All kinds: pole_separation (default 0.85 x the part's length along x; soft
// iron's: its length, its poles on its faces).
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
inline constexpr const char* kCoreDiameter = "core_diameter";
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

/// Upper bounds of magnetism's own inputs (docs/security.md). A coil of 1e7
/// turns is far beyond a real one (a laboratory solenoid has 1e3 to 1e5), and
/// an iron core multiplies the air-core coil_factor (cross-section over pole
/// separation, under 1 m for any part the bounds allow) by at most its
/// relative permeability, a few thousand: 1e4 m. Beyond them a coil drove the
/// strong-coupling instability to overflow before anything named the coil.
inline constexpr double kMaxTurns = 1e7;
inline constexpr double kMaxCoilFactor = 1e4;

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
      susceptibility, saturation_pole, core_diameter;
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
        susceptibility, saturation_pole, core_diameter, position, orientation, shape, size, radius,
        length;
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
  double aspect_ratio = 1;   ///< length / equivalent diameter
  /// Full extents along local x, y, z, m (box: size; sphere: 2r each;
  /// capsule: length + 2r, 2r, 2r): the ellipsoid its demagnetising
  /// factors are taken from.
  Vec3 extent;
  enum class Shape : std::uint8_t { Box, Sphere, Capsule } shape = Shape::Box;
  double radius = 0;  ///< sphere and capsule, m
};

/// Length of the chord through the part's centre along the unit direction
/// `u` (local frame), m: where the poles of a moment along u are spread.
double chord(const PartBulk& bulk, Vec3 u);

/// The part's bulk geometry, or nullopt if it carries no usable shape.
std::optional<PartBulk> part_bulk(const MagnetColumns& c, std::uint32_t slot);

/// Distance between the part's two poles, m: `pole_separation` if carried,
/// else kMagneticLengthRatio times the shape's length (soft iron: kInducedLengthRatio);
/// nullopt if neither.
std::optional<double> pole_separation(const MagnetColumns& c, std::uint32_t slot);

/// Pole strength per ampere-turn of an electromagnet, m: `coil_factor` if
/// carried, else cross-section / pole separation (an air-core solenoid's
/// moment N I A spread over its poles); nullopt if the geometry is missing.
std::optional<double> coil_factor(const MagnetColumns& c, std::uint32_t slot);

/// What the induction solve needs of a soft-iron part (or of a coil's iron
/// core), in the part's local frame (magnetic_forces turns it into an
/// InducedPart at the part's pose).
struct SoftIronModel {
  Vec3 susceptibility;    ///< apparent chi along local x, y, z: chi / (1 + N_i chi)
  Vec3 separation;        ///< pole separation along local x, y, z, m
  double volume = 0;      ///< of the iron, m^3
  double saturation = 0;  ///< largest moment, A*m^2
  /// Pole separation of a moment along the local unit direction u, m: the
  /// chord along u scaled like the x axis's (1: the faces, by default). Unused for a
  /// coil's core, whose moment stays on the coil's axis.
  double separation_along(Vec3 u) const { return chord_scale * chord(bulk, u); }
  PartBulk bulk;
  double chord_scale = 0;
  bool axial_only = false;  ///< a coil's core: magnetised along local x only
};
/// The model of a soft-iron part, or of an electromagnet's iron core (an
/// electromagnet carrying `susceptibility`); nullopt without one.
std::optional<SoftIronModel> soft_iron_model(const MagnetColumns& c, std::uint32_t slot);

/// Why a magnetic part cannot be simulated ("" if it can): the message names
/// what is missing, for the scene author.
std::string check_part(const MagnetColumns& c, std::uint32_t slot);

}  // namespace alloy::magnetism
