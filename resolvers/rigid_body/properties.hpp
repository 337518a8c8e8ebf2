// Property types of rigid bodies, joints and contact materials. The names are a
// contract with the Lua kit and the viewer: keep them exactly.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "runtime/property_types.hpp"
#include "runtime/world.hpp"

namespace alloy::rigid {

/// Values of the `shape` enum, in registry order. A cylinder's axis is the
/// part's z axis: a planar cylinder is a disk in the play area (a wheel, a
/// coin, a pulley), `length` its thickness out of the plane.
enum class Shape : std::int32_t { Box = 0, Sphere = 1, Capsule = 2, Cylinder = 3 };
/// Values of the `joint` enum, in registry order.
enum class JointType : std::int32_t { Hinge = 0, Fixed = 1 };

/// What a rigid body may be, in SI units. Inside these bounds ODE's arithmetic
/// (bounding boxes, the normalisation of rotations, the solver's rows) stays
/// finite and keeps the precision that contacts need. An edit beyond them
/// (a scene, the viewer, the timeline, a Lua resolver's write) is refused by
/// the property registry; a load, a mass or a motion that would take a body
/// beyond them is refused by the rigid body, which freezes the body (an
/// "out_of_bounds" event naming the stage that gave the value).
namespace limits {
/// Every coordinate of a body's centre (and of a hinge's pivot), m. At 1e6 m
/// a double resolves 1.2e-10 m, six orders below the contact surface layer
/// (1e-4 m), and squared distances (1e12 m^2) are far from overflowing.
inline constexpr double extent = 1e6;
/// Every component of a velocity, m/s: 100 km/s, nine times the Earth's
/// escape velocity and twenty times the speed of sound in steel. At the
/// default step a body moves at most 420 m a step.
inline constexpr double speed = 1e5;
/// Every component of an angular velocity, rad/s (a million rpm): a rim
/// 1 m out at the speed limit.
inline constexpr double angular_speed = 1e5;
/// A moving body's mass, kg: a microgram to a billion tonnes. A lighter body
/// (1e-300 kg) makes inverse masses and inertias that overflow the solver.
inline constexpr double min_mass = 1e-9, max_mass = 1e12;
/// A moving body's smallest principal moment of inertia, kg m^2 (a microgram
/// sphere of radius 0.1 mm has 4e-18): below it the inertia is not positive
/// definite in floating point (ODE asserts) or its inverse overflows.
inline constexpr double min_inertia = 1e-24;
/// A part's dimensions (size, radius, length), m: within the extent.
inline constexpr double max_dimension = extent;
/// Contact pairs a part keeps a step: a pair of overlapping parts is left
/// out (before its narrow phase or its contact is made) when each of its two
/// parts already touches this many moving parts, so a step holds at most
/// this many pairs a part. Parts that do not overlap touch few others (a
/// disk among packed disks 6, a sphere among packed spheres 12), and a part
/// touching many (a tray of marbles) keeps them all while its partners touch
/// few. A heap of parts placed through each other (n parts at one spot make
/// n^2 / 2 pairs: 500,000 for 1,000) would cost the engines seconds and
/// gigabytes a step; its pairs past the limit are left out, with an event
/// naming the parts (docs/security.md).
inline constexpr std::uint32_t contact_pairs_per_part = 32;
}  // namespace limits

/// Body properties: pose, velocity, mass and shape (see the doc line of each).
std::vector<PropertyDef> body_properties();
/// The one body property called `name` (for plugins that read a few of them,
/// such as gravity's); std::logic_error if there is none.
PropertyDef body_property(std::string_view name);
/// Joint objects: joint, body_a, body_b, anchor, axis, joint_friction, limits.
std::vector<PropertyDef> joint_properties();
/// Contact materials: friction, restitution.
std::vector<PropertyDef> material_properties();

/// Whole-object check of the rigid body (the plugin's PluginDef::check): a
/// shape with its dimensions, a moving body with a mass, a joint between two
/// distinct bodies with ordered limits. Throws InputError without a location.
void check_object(const World& world, ObjectId id);

/// Volume of a part's shape, m^3 (for mass = density * volume).
double shape_volume(Shape shape, Vec3 size, double radius, double length);

/// Principal moments of inertia of a solid cylinder of mass m, radius r and
/// length len along its axis (the part's z), about its centre of mass, kg m^2:
/// {m (3 r^2 + len^2) / 12, the same, m r^2 / 2}.
Vec3 cylinder_inertia(double mass, double radius, double length);

}  // namespace alloy::rigid
