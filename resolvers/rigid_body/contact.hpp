// Contact data shared by the collisions derived set, the interaction that feeds
// contacts to the rigid body, and the rigid body's published impulses.
#pragma once

#include <cstdint>

#include "runtime/math.hpp"
#include "runtime/object_id.hpp"

namespace alloy::rigid {

/// One point of contact between two parts a and b (a < b by ObjectId).
struct ContactPoint {
  Vec3 position;      ///< world frame, m
  /// Unit normal pointing from b towards a: moving a along +normal by `depth`
  /// separates the parts (ODE's convention with a as body 1).
  Vec3 normal;
  double depth = 0;   ///< penetration, m (>= 0)
};

/// The impulse the rigid body applied to a pair of parts over its last advance.
struct PairImpulse {
  ObjectId a, b;             ///< a < b
  Vec3 impulse;              ///< total contact impulse on a (normal and friction), N*s; b got -impulse
  double normal_impulse = 0; ///< its normal part, N*s (>= 0)
};

/// Orders pairs by (a, b): the deterministic order of every contact list.
constexpr bool pair_less(ObjectId a1, ObjectId b1, ObjectId a2, ObjectId b2) {
  return a1 < a2 || (a1 == a2 && b1 < b2);
}

}  // namespace alloy::rigid
