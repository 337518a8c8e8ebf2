// Checks a scene's values must pass before any resolver (and so ODE) sees
// them, beyond what the property registry knows (kind, finiteness, a lower
// bound): a mass must be strictly positive, a restitution lies in [0, 1], a
// box needs a size, a joint needs a body. They are keyed by the property names
// of the rigid-body contract (resolvers/plugins.hpp); a property a scene does
// not use costs nothing. Nothing here knows Lua.
#pragma once

#include "runtime/property_types.hpp"
#include "runtime/world.hpp"

namespace alloy::lua {

/// Throws InputError (without a location) if `value` is not acceptable for
/// the property `def`.
void check_value(const PropertyDef& def, const PropertyValue& value);

/// Throws InputError (without a location) if the object's properties do not
/// make sense together (a sphere without a radius, a joint without body_a,
/// limit_low above limit_high, a moving body without mass).
void check_object(const World& world, ObjectId id);

}  // namespace alloy::lua
