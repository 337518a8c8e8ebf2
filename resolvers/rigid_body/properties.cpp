#include "resolvers/rigid_body/properties.hpp"

#include <numbers>

namespace alloy::rigid {

namespace {
PropertyDef number(const char* name, const char* unit, const char* doc, std::optional<double> min = {}) {
  return {.name = name, .kind = PropertyKind::Number, .unit = unit, .doc = doc, .min = min};
}
PropertyDef vec3(const char* name, const char* unit, const char* doc) {
  return {.name = name, .kind = PropertyKind::Vec3, .unit = unit, .doc = doc};
}
PropertyDef boolean(const char* name, const char* doc) {
  return {.name = name, .kind = PropertyKind::Bool, .doc = doc};
}
}  // namespace

std::vector<PropertyDef> body_properties() {
  return {
      vec3("position", "m", "position of the part's centre of mass, world frame"),
      {.name = "orientation", .kind = PropertyKind::Quat, .doc = "rotation from the part's frame to the world frame"},
      vec3("velocity", "m/s", "linear velocity of the part's centre of mass"),
      vec3("angular_velocity", "rad/s", "angular velocity, world frame"),
      number("mass", "kg", "mass (must be > 0); written from density * volume when density is given", 0.0),
      number("density", "kg/m^3", "density; when given, mass = density * volume of the shape", 0.0),
      {.name = "shape", .kind = PropertyKind::Enum, .doc = "collision and inertia shape",
       .enum_values = {"box", "sphere", "capsule"}},
      vec3("size", "m", "box: full extents along the part's x, y, z"),
      number("radius", "m", "sphere and capsule radius", 0.0),
      number("length", "m", "capsule: length of the cylinder part, along the part's x axis", 0.0),
      boolean("static", "immovable geometry with no body (floor, walls)"),
      boolean("pinned", "fixed to the play area; keeps its mass and can be unpinned"),
      boolean("planar", "held to the z = 0 plane, rotating about z only (the 2D kit)"),
      number("linear_damping", "1/s", "velocity decays as dv/dt = -c v", 0.0),
      number("angular_damping", "1/s", "angular velocity decays as dw/dt = -c w", 0.0),
  };
}

std::vector<PropertyDef> joint_properties() {
  return {
      {.name = "joint", .kind = PropertyKind::Enum, .doc = "this object is a joint of this type",
       .enum_values = {"hinge", "fixed"}},
      {.name = "body_a", .kind = PropertyKind::Ref, .doc = "first joined part"},
      {.name = "body_b", .kind = PropertyKind::Ref, .doc = "second joined part; absent or null: the play area"},
      vec3("anchor", "m", "hinge pivot, world frame (kept current by the rigid body resolver)"),
      vec3("axis", "", "hinge axis, world frame (default {0,0,1}; kept current by the resolver)"),
      number("joint_friction", "N*m", "hinge: resisting torque of the pivot", 0.0),
      number("limit_low", "rad", "hinge: lowest angle of body_a relative to body_b about the axis"),
      number("limit_high", "rad", "hinge: highest angle of body_a relative to body_b about the axis"),
  };
}

std::vector<PropertyDef> material_properties() {
  return {
      number("friction", "", "Coulomb friction coefficient (default 0.5)", 0.0),
      number("restitution", "", "coefficient of restitution, 0..1 (default 0)", 0.0),
  };
}

double shape_volume(Shape shape, Vec3 size, double radius, double length) {
  constexpr double pi = std::numbers::pi;
  switch (shape) {
    case Shape::Box: return size.x * size.y * size.z;
    case Shape::Sphere: return 4.0 / 3.0 * pi * radius * radius * radius;
    case Shape::Capsule: return pi * radius * radius * length + 4.0 / 3.0 * pi * radius * radius * radius;
  }
  return 0;
}

}  // namespace alloy::rigid
