#include "resolvers/magnetism/magnet_parts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "resolvers/magnetism/pole_model.hpp"

namespace alloy::magnetism {

std::vector<PropertyDef> magnetism_property_defs() {
  using K = PropertyKind;
  return {
      {.name = prop::kMagnet,
       .kind = K::Enum,
       .doc = "kind of magnetic part; carrying it makes the object magnetic",
       .enum_values = {"permanent", "electromagnet", "soft_iron"}},
      {.name = prop::kPoleStrength,
       .kind = K::Number,
       .unit = "A*m",
       .doc = "pole strength q: north (+q) at the local +x end when positive, at -x when "
              "negative; set for permanent magnets, written by magnetism for electromagnets"},
      {.name = prop::kPoleSeparation,
       .kind = K::Number,
       .unit = "m",
       .doc = "distance between the two poles along local x; default 0.85 x the part's length",
       .min = 0.0},
      {.name = prop::kTurns,
       .kind = K::Number,
       .unit = "1",
       .doc = "electromagnet: number of turns N of the coil",
       .min = 0.0,
       .max = kMaxTurns},
      {.name = prop::kCoilFactor,
       .kind = K::Number,
       .unit = "m",
       .doc = "electromagnet: pole strength per ampere-turn, q = coil_factor N I; default "
              "cross-section / pole_separation (air core); an iron core multiplies it",
       .min = 0.0,
       .max = kMaxCoilFactor},
      {.name = prop::kCoilTimeConstant,
       .kind = K::Number,
       .unit = "s",
       .doc = "electromagnet: time constant with which the pole strength follows the current "
              "(0: at the next step)",
       .min = 0.0},
      {.name = prop::kSusceptibility,
       .kind = K::Number,
       .unit = "1",
       .doc = "soft iron: intrinsic volume susceptibility chi (iron: 100 to 5000); on an "
              "electromagnet, that of its iron core",
       .min = 0.0},
      {.name = prop::kSaturationPole,
       .kind = K::Number,
       .unit = "A*m",
       .doc = "soft iron: largest induced pole strength; default from iron's saturation "
              "magnetisation 1.71e6 A/m x volume / pole_separation",
       .min = 0.0},
      {.name = prop::kCoreDiameter,
       .kind = K::Number,
       .unit = "m",
       .doc = "electromagnet with a susceptibility: diameter of its soft-iron core, a rod "
              "along x as long as the part; default the diameter of the part's cross-section",
       .min = 0.0},
      {.name = prop::kPoleStrengthRate,
       .kind = K::Number,
       .unit = "A*m/s",
       .doc = "written by magnetism with rates = true: an electromagnet's d pole_strength / dt"},
  };
}

void ensure_geometry_properties(PropertyRegistry& registry) {
  using K = PropertyKind;
  const PropertyDef defs[] = {
      {.name = prop::kPosition, .kind = K::Vec3, .unit = "m", .doc = "centre of mass, world frame"},
      {.name = prop::kOrientation, .kind = K::Quat, .doc = "rotation from body to world frame"},
      {.name = prop::kShape,
       .kind = K::Enum,
       .doc = "collision shape",
       .enum_values = {"box", "sphere", "capsule", "cylinder"}},  // as the rigid body's
      {.name = prop::kSize,
       .kind = K::Vec3,
       .unit = "m",
       .doc = "box: full extents along local x, y, z"},
      {.name = prop::kRadius,
       .kind = K::Number,
       .unit = "m",
       .doc = "sphere and capsule radius",
       .min = 0.0},
      {.name = prop::kLength,
       .kind = K::Number,
       .unit = "m",
       .doc = "capsule: length of the cylinder part, along local x",
       .min = 0.0},
  };
  for (const PropertyDef& d : defs)
    if (!registry.find(d.name)) {
      PropertyDef copy = d;
      copy.owner = "magnetism";
      registry.add(std::move(copy));
    }
}

MagnetColumns::Ids MagnetColumns::Ids::resolve(const WorldView& w) {
  Ids i{.magnet = w.property(prop::kMagnet),
        .pole_strength = w.property(prop::kPoleStrength),
        .pole_separation = w.property(prop::kPoleSeparation),
        .turns = w.property(prop::kTurns),
        .coil_factor = w.property(prop::kCoilFactor),
        .coil_time_constant = w.property(prop::kCoilTimeConstant),
        .susceptibility = w.property(prop::kSusceptibility),
        .saturation_pole = w.property(prop::kSaturationPole),
        .core_diameter = w.property(prop::kCoreDiameter),
        .position = w.property(prop::kPosition),
        .orientation = w.property(prop::kOrientation),
        .shape = w.property(prop::kShape),
        .size = w.property(prop::kSize),
        .radius = w.property(prop::kRadius),
        .length = w.property(prop::kLength)};
  auto index = [&](const char* name) {
    auto v = w.properties().enum_value(i.shape, name);
    return v ? v->index : -1;
  };
  i.shape_box = index("box");
  i.shape_sphere = index("sphere");
  i.shape_capsule = index("capsule");
  return i;
}

MagnetColumns MagnetColumns::bind(const WorldView& w, const Ids& i) {
  MagnetColumns c;
  c.magnet = w.column<EnumValue>(i.magnet);
  c.pole_strength = w.column<double>(i.pole_strength);
  c.pole_separation = w.column<double>(i.pole_separation);
  c.turns = w.column<double>(i.turns);
  c.coil_factor = w.column<double>(i.coil_factor);
  c.coil_time_constant = w.column<double>(i.coil_time_constant);
  c.susceptibility = w.column<double>(i.susceptibility);
  c.saturation_pole = w.column<double>(i.saturation_pole);
  c.core_diameter = w.column<double>(i.core_diameter);
  c.position = w.column<Vec3>(i.position);
  c.orientation = w.column<Quat>(i.orientation);
  c.shape = w.column<EnumValue>(i.shape);
  c.size = w.column<Vec3>(i.size);
  c.radius = w.column<double>(i.radius);
  c.length = w.column<double>(i.length);
  c.shape_box = i.shape_box;
  c.shape_sphere = i.shape_sphere;
  c.shape_capsule = i.shape_capsule;
  return c;
}

std::optional<PartBulk> part_bulk(const MagnetColumns& c, std::uint32_t slot) {
  if (!c.shape.has(slot)) return std::nullopt;
  constexpr double pi = std::numbers::pi;
  const int shape = c.shape[slot].index;
  PartBulk b;
  if (shape == c.shape_box && c.size.has(slot)) {
    const Vec3 s = c.size[slot];
    b.length = s.x;
    b.cross_section = s.y * s.z;
    b.volume = s.x * s.y * s.z;
    // Diameter of the circle with the same cross-section.
    const double diameter = std::sqrt(4.0 * b.cross_section / pi);
    b.aspect_ratio = diameter > 0 ? b.length / diameter : 1.0;
    b.extent = s;
    b.shape = PartBulk::Shape::Box;
  } else if (shape == c.shape_sphere && c.radius.has(slot)) {
    const double r = c.radius[slot];
    b.length = 2 * r;
    b.cross_section = pi * r * r;
    b.volume = 4.0 / 3.0 * pi * r * r * r;
    b.aspect_ratio = 1.0;
    b.extent = {2 * r, 2 * r, 2 * r};
    b.shape = PartBulk::Shape::Sphere;
    b.radius = r;
  } else if (shape == c.shape_capsule && c.radius.has(slot) && c.length.has(slot)) {
    const double r = c.radius[slot], l = c.length[slot];
    b.length = l + 2 * r;
    b.cross_section = pi * r * r;
    b.volume = pi * r * r * l + 4.0 / 3.0 * pi * r * r * r;
    b.aspect_ratio = r > 0 ? b.length / (2 * r) : 1.0;
    b.extent = {l + 2 * r, 2 * r, 2 * r};
    b.shape = PartBulk::Shape::Capsule;
    b.radius = r;
  } else {
    return std::nullopt;
  }
  if (!(b.length > 0) || !(b.cross_section > 0) || !std::isfinite(b.volume)) return std::nullopt;
  return b;
}

std::optional<double> pole_separation(const MagnetColumns& c, std::uint32_t slot) {
  if (c.pole_separation.has(slot)) return c.pole_separation[slot];
  if (auto b = part_bulk(c, slot)) {
    // Soft iron's induced poles lie on its faces (a uniformly magnetised
    // body's pole density is M.n on its surface), where a gap to a coil or a
    // magnet is measured: 0.85 L, a bar magnet's effective length, put them
    // 0.075 L inside each face and made the pull across a few millimetres
    // too weak to lift the kit's armature (docs/magnetism.md "Soft iron").
    const bool iron = c.magnet.has(slot) && c.kind(slot) == MagnetKind::SoftIron;
    return (iron ? kInducedLengthRatio : kMagneticLengthRatio) * b->length;
  }
  return std::nullopt;
}

std::optional<double> coil_factor(const MagnetColumns& c, std::uint32_t slot) {
  if (c.coil_factor.has(slot)) return c.coil_factor[slot];
  const auto b = part_bulk(c, slot);
  const auto d = pole_separation(c, slot);
  if (!b || !d || !(*d > 0)) return std::nullopt;
  return b->cross_section / *d;
}

double chord(const PartBulk& b, Vec3 u) {
  const Vec3 a{std::abs(u.x), std::abs(u.y), std::abs(u.z)};
  switch (b.shape) {
    case PartBulk::Shape::Sphere:
      return 2 * b.radius;
    case PartBulk::Shape::Capsule: {
      // Half-chord t: t u is a radius from the axis segment [-l/2, l/2] x.
      const double half = 0.5 * (b.extent.x - 2 * b.radius), r = b.radius;
      const double across = std::sqrt(std::max(0.0, 1.0 - a.x * a.x));
      if (across > 0 && r / across * a.x <= half) return 2 * r / across;
      // Through the end cap: |t u - half x|^2 = r^2.
      const double t =
          half * a.x + std::sqrt(std::max(0.0, half * half * a.x * a.x - half * half + r * r));
      return 2 * t;
    }
    case PartBulk::Shape::Box:
    default: {
      double t = std::numeric_limits<double>::infinity();
      if (a.x > 0) t = std::min(t, b.extent.x / a.x);
      if (a.y > 0) t = std::min(t, b.extent.y / a.y);
      if (a.z > 0) t = std::min(t, b.extent.z / a.z);
      return std::isfinite(t) ? t : b.length;
    }
  }
}

std::optional<SoftIronModel> soft_iron_model(const MagnetColumns& c, std::uint32_t slot) {
  const auto b = part_bulk(c, slot);
  const auto d = pole_separation(c, slot);
  if (!b || !d || !(*d > 0)) return std::nullopt;
  const double chi = c.susceptibility.value_or(slot, 0.0);
  SoftIronModel m;
  m.bulk = *b;
  m.chord_scale = *d / b->length;  // kMagneticLengthRatio unless pole_separation says otherwise
  if (c.kind(slot) == MagnetKind::Electromagnet) {
    // The core: a rod along x, as long as the coil, magnetised along the
    // coil's axis only (its transverse apparent chi is at most 2, against
    // 1/N_x along it; and one pole pair carries the coil and its core).
    const double dc =
        c.core_diameter.value_or(slot, std::sqrt(4.0 * b->cross_section / std::numbers::pi));
    if (!(dc > 0) || !std::isfinite(dc)) return std::nullopt;
    m.axial_only = true;
    m.volume = std::numbers::pi / 4 * dc * dc * b->length;
    m.susceptibility = {apparent_susceptibility(chi, demagnetizing_factor(b->length / dc)), 0, 0};
    m.separation = {*d, kMagneticLengthRatio * dc, kMagneticLengthRatio * dc};
  } else {
    // A box: the prism's own factors; a sphere or a capsule: the ellipsoid's
    // (for a capsule, the spheroid of its length and diameter).
    const Vec3 n = b->shape == PartBulk::Shape::Box ? prism_demagnetizing_factors(b->extent * 0.5)
                                                    : demagnetizing_factors(b->extent * 0.5);
    m.volume = b->volume;
    m.susceptibility = {apparent_susceptibility(chi, n.x), apparent_susceptibility(chi, n.y),
                        apparent_susceptibility(chi, n.z)};
    m.separation = {m.separation_along({1, 0, 0}), m.separation_along({0, 1, 0}),
                    m.separation_along({0, 0, 1})};
  }
  // saturation_pole is a pole strength along x: the moment at saturation is it times d.
  m.saturation = c.saturation_pole.has(slot) ? c.saturation_pole[slot] * *d
                                             : kIronSaturationMagnetization * m.volume;
  return m;
}

std::string check_part(const MagnetColumns& c, std::uint32_t slot) {
  if (!c.position.has(slot)) return "a magnet needs a 'position'";
  if (auto d = pole_separation(c, slot); d && !(*d > 0))
    return "'pole_separation' must be positive: poles at one point cancel";
  switch (c.kind(slot)) {
    case MagnetKind::Permanent:
      if (!pole_separation(c, slot))
        return "a permanent magnet needs 'pole_separation' or a shape (box 'size', sphere "
               "'radius', capsule 'radius' and 'length')";
      return "";
    case MagnetKind::Electromagnet:
      if (!pole_separation(c, slot) || !coil_factor(c, slot))
        return "an electromagnet needs a shape (box 'size', sphere 'radius', capsule 'radius' "
               "and 'length'), or 'pole_separation' and 'coil_factor'";
      if (c.susceptibility.has(slot) && !soft_iron_model(c, slot))
        return "an electromagnet with an iron core ('susceptibility') needs a shape (box 'size', "
               "sphere 'radius', capsule 'radius' and 'length') and a positive 'core_diameter'";
      return "";
    case MagnetKind::SoftIron:
      if (!c.susceptibility.has(slot)) return "soft iron needs a 'susceptibility'";
      if (!soft_iron_model(c, slot))
        return "soft iron needs a shape (box 'size', sphere 'radius', capsule 'radius' and "
               "'length') for its volume";
      return "";
  }
  return "unknown kind of magnet";
}

}  // namespace alloy::magnetism
