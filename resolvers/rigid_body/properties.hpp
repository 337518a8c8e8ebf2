// Property types of rigid bodies, joints and contact materials. The names are a
// contract with the Lua kit and the viewer: keep them exactly.
#pragma once

#include <vector>

#include "runtime/property_types.hpp"
#include "runtime/world.hpp"

namespace alloy::rigid {

/// Values of the `shape` enum, in registry order.
enum class Shape : std::int32_t { Box = 0, Sphere = 1, Capsule = 2 };
/// Values of the `joint` enum, in registry order.
enum class JointType : std::int32_t { Hinge = 0, Fixed = 1 };

/// Body properties: pose, velocity, mass and shape (see the doc line of each).
std::vector<PropertyDef> body_properties();
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

}  // namespace alloy::rigid
