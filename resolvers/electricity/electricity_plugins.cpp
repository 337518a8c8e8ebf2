#include "resolvers/electricity/electricity_plugins.hpp"

#include "resolvers/electricity/electricity.hpp"
#include "resolvers/electricity/electricity_from_collisions.hpp"

namespace alloy::electricity {

void register_electricity_plugins(PluginRegistry& registry) {
  register_electricity_resolver(registry);
  register_electricity_from_collisions(registry);
}

}  // namespace alloy::electricity
