// The `alloy` command line: run, check, plugins. Kept apart from main() so that
// tests can call it in-process with their own streams.
#pragma once

#include <ostream>

namespace alloy::app {

/// Exit codes: 0 success, 2 bad input (scene, mod, arguments), 1 other failure.
inline constexpr int kExitOk = 0, kExitFailure = 1, kExitBadInput = 2;

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace alloy::app
