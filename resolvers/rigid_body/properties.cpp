#include "resolvers/rigid_body/properties.hpp"

#include <cstdio>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

namespace alloy::rigid {

namespace {
// Bounds are declared with the types, so every edit (scene, viewer, timeline)
// is checked in one place, the property store.
PropertyDef number(const char* name, const char* unit, const char* doc) {
  return {.name = name, .kind = PropertyKind::Number, .unit = unit, .doc = doc};
}
PropertyDef positive(const char* name, const char* unit, const char* doc) {
  return {.name = name,
          .kind = PropertyKind::Number,
          .unit = unit,
          .doc = doc,
          .min = 0.0,
          .min_exclusive = true};
}
PropertyDef non_negative(const char* name, const char* unit, const char* doc) {
  return {.name = name, .kind = PropertyKind::Number, .unit = unit, .doc = doc, .min = 0.0};
}
PropertyDef vec3(const char* name, const char* unit, const char* doc) {
  return {.name = name, .kind = PropertyKind::Vec3, .unit = unit, .doc = doc};
}
PropertyDef boolean(const char* name, const char* doc) {
  return {.name = name, .kind = PropertyKind::Bool, .doc = doc};
}
// Physical bounds (limits::): every component in [-bound, bound], or at most `bound`.
PropertyDef within(PropertyDef def, double bound) {
  def.min = -bound, def.max = bound;
  return def;
}
PropertyDef at_most(PropertyDef def, double bound) {
  def.max = bound;
  return def;
}
}  // namespace

std::vector<PropertyDef> body_properties() {
  return {
      within(vec3("position", "m", "position of the part's centre of mass, world frame"),
             limits::extent),
      {.name = "orientation",
       .kind = PropertyKind::Quat,
       .doc = "rotation from the part's frame to the world frame",
       .nonzero = true},
      within(vec3("velocity", "m/s", "linear velocity of the part's centre of mass"),
             limits::speed),
      within(vec3("angular_velocity", "rad/s", "angular velocity, world frame"),
             limits::angular_speed),
      at_most(positive("mass", "kg",
                       "mass (must be > 0); written from density * volume when density is given"),
              limits::max_mass),
      positive("density", "kg/m^3", "density; when given, mass = density * volume of the shape"),
      {.name = "shape",
       .kind = PropertyKind::Enum,
       .doc = "collision and inertia shape",
       .enum_values = {"box", "sphere", "capsule", "cylinder"}},
      {.name = "size",
       .kind = PropertyKind::Vec3,
       .unit = "m",
       .doc = "box: full extents along the part's x, y, z",
       .min = 0.0,
       .min_exclusive = true,
       .max = limits::max_dimension},
      at_most(positive("radius", "m", "sphere, capsule and cylinder radius"),
              limits::max_dimension),
      at_most(non_negative("length", "m",
                           "capsule: length of the cylinder part, along the part's x axis; "
                           "cylinder: its length (a disk's thickness), along the part's z axis"),
              limits::max_dimension),
      boolean("static", "immovable geometry with no body (floor, walls)"),
      boolean("pinned", "fixed to the play area; keeps its mass and can be unpinned"),
      boolean("planar", "held to the z = 0 plane, rotating about z only (the 2D kit)"),
      non_negative("linear_damping", "1/s", "velocity decays as dv/dt = -c v"),
      non_negative("angular_damping", "1/s", "angular velocity decays as dw/dt = -c w"),
  };
}

PropertyDef body_property(std::string_view name) {
  for (PropertyDef& d : body_properties())
    if (d.name == name) return std::move(d);
  throw std::logic_error("no body property '" + std::string(name) + "'");
}

std::vector<PropertyDef> joint_properties() {
  return {
      {.name = "joint",
       .kind = PropertyKind::Enum,
       .doc = "this object is a joint of this type",
       .enum_values = {"hinge", "fixed"}},
      {.name = "body_a", .kind = PropertyKind::Ref, .doc = "first joined part"},
      {.name = "body_b",
       .kind = PropertyKind::Ref,
       .doc = "second joined part; absent or null: the play area"},
      within(
          vec3("anchor", "m", "hinge pivot, world frame (kept current by the rigid body resolver)"),
          limits::extent),
      within(
          vec3("anchor_a", "m",
               "hinge pivot in body_a's frame, or a world point for the play area (set from anchor "
               "at the first build; swaps, restores and rebuilds keep the joint at it)"),
          limits::extent),
      within(vec3("anchor_b", "m",
                  "hinge pivot in body_b's frame, or a world point for the play area (set "
                  "from anchor at the first build)"),
             limits::extent),
      {.name = "axis",
       .kind = PropertyKind::Vec3,
       .doc = "hinge axis, world frame (default {0,0,1}; kept current by the resolver)",
       .nonzero = true},
      non_negative("joint_friction", "N*m", "hinge: resisting torque of the pivot"),
      number("limit_low", "rad", "hinge: lowest angle of body_a relative to body_b about the axis"),
      number("limit_high", "rad",
             "hinge: highest angle of body_a relative to body_b about the axis"),
  };
}

std::vector<PropertyDef> material_properties() {
  return {
      non_negative("friction", "", "Coulomb friction coefficient (default 0.5)"),
      {.name = "restitution",
       .kind = PropertyKind::Number,
       .doc = "coefficient of restitution, 0..1 (default 0)",
       .min = 0.0,
       .max = 1.0},
  };
}

namespace {
bool carries(const World& w, ObjectId id, const char* property) {
  auto p = w.properties().find(property);
  return p && w.store().has(id, *p);
}
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
}  // namespace

void check_object(const World& w, ObjectId id) {
  if (carries(w, id, "joint")) {
    auto a = w.value<ObjectId>(id, "body_a");
    if (!a || a->is_null()) throw InputError("a joint needs 'body_a', the body it holds");
    auto b = w.value<ObjectId>(id, "body_b");
    if (b && *b == *a) throw InputError("a joint cannot join '" + w.describe(*a) + "' to itself");
    for (ObjectId body : {*a, b.value_or(ObjectId{})}) {
      if (body.is_null()) continue;
      if (carries(w, body, "joint"))
        throw InputError("a joint can only hold bodies, and '" + w.describe(body) + "' is a joint");
      if (!carries(w, body, "shape"))
        throw InputError("a joint can only hold bodies, and '" + w.describe(body) +
                         "' has no shape");
    }
    auto lo = w.value<double>(id, "limit_low");
    auto hi = w.value<double>(id, "limit_high");
    if (lo && hi && *lo > *hi)
      throw InputError("'limit_low' (" + num(*lo) + ") is above 'limit_high' (" + num(*hi) + ")");
    return;
  }
  auto shape = w.value<EnumValue>(id, "shape");
  if (!shape) return;
  switch (Shape(shape->index)) {
    case Shape::Box:
      if (!carries(w, id, "size"))
        throw InputError("a box needs a 'size' (full extents {x, y, z})");
      break;
    case Shape::Sphere:
      if (!carries(w, id, "radius")) throw InputError("a sphere needs a 'radius'");
      break;
    case Shape::Capsule:
      if (!carries(w, id, "radius") || !carries(w, id, "length"))
        throw InputError("a capsule needs a 'radius' and a 'length'");
      break;
    case Shape::Cylinder:
      if (!carries(w, id, "radius") || !carries(w, id, "length"))
        throw InputError(
            "a cylinder needs a 'radius' and a 'length' (its thickness along the part's z)");
      break;
  }
  if (!w.value<bool>(id, "static").value_or(false) && !carries(w, id, "mass") &&
      !carries(w, id, "density"))
    throw InputError(
        "a moving body needs a 'mass' (or 'density'); give one, or make it static = true");
}

double shape_volume(Shape shape, Vec3 size, double radius, double length) {
  constexpr double pi = std::numbers::pi;
  switch (shape) {
    case Shape::Box:
      return size.x * size.y * size.z;
    case Shape::Sphere:
      return 4.0 / 3.0 * pi * radius * radius * radius;
    case Shape::Capsule:
      return pi * radius * radius * length + 4.0 / 3.0 * pi * radius * radius * radius;
    case Shape::Cylinder:
      return pi * radius * radius * length;
  }
  return 0;
}

Vec3 cylinder_inertia(double mass, double radius, double length) {
  const double across = mass * (3 * radius * radius + length * length) / 12;
  return {across, across, 0.5 * mass * radius * radius};
}

}  // namespace alloy::rigid
