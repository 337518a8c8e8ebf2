// The Box2D rigid body's plugins (box2d_engine.hpp).
#pragma once

#include "runtime/plugin_registry.hpp"

namespace alloy::box2d {

/// Registers `rigid_body.box2d` (resolver, provides rigid_body) and
/// `collisions.box2d` (derived set, provides collisions).
void register_rigid_body_box2d_plugins(PluginRegistry& registry);

}  // namespace alloy::box2d
