#include "resolvers/sound/sound_plugins.hpp"

#include "resolvers/sound/sound_from_collisions.hpp"
#include "resolvers/sound/sound_resolver.hpp"

namespace alloy::sound {

void register_sound_plugins(PluginRegistry& registry) {
  register_sound_resolver(registry);
  register_sound_from_collisions(registry);
}

}  // namespace alloy::sound
