// `alloy run --profile`: time per step of each stage and phase, its share,
// and the plugins that were not instantiated because nothing needed them.
#pragma once

#include <ostream>

#include "runtime/profile.hpp"

namespace alloy::app {

void print_profile(std::ostream& out, const Profile& profile);

}  // namespace alloy::app
