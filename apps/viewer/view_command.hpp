// `alloy view SCENE`: the viewer as a subcommand of the alloy command line.
#pragma once

#include <ostream>

#include "apps/viewer/viewer_options.hpp"

namespace CLI {
class App;
}

namespace alloy::viewer {

/// Adds the `view` subcommand to `app`, filling `options` when it is parsed.
CLI::App* add_view_command(CLI::App& app, ViewerOptions& options);

/// Runs the viewer. Exit codes as the rest of alloy: 0, 2 bad input (a scene
/// that does not load, a bad script), 1 other failure (no display, a file
/// that cannot be written).
int run_view(ViewerOptions options, std::ostream& out, std::ostream& err);

}  // namespace alloy::viewer
