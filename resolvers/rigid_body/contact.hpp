// Contact data shared by the collisions derived set, the interaction that feeds
// contacts to the rigid body, and the rigid body's published impulses.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "runtime/contact_set.hpp"

namespace alloy::rigid {

// The contact types are the runtime's (runtime/contact_set.hpp): every engine
// publishes them. These names keep the rigid body's code in its own namespace.
using alloy::ContactPair;
using alloy::ContactPoint;
using alloy::ContactSet;
using alloy::ImpulseDemand;
using alloy::pair_less;
using alloy::PairImpulse;

}  // namespace alloy::rigid
