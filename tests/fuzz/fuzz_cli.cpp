// The CLI target (fuzz_entries.hpp, cli): apart from the others because it
// needs the whole `alloy` command, viewer included, to link.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "apps/alloy/commands.hpp"
#include "tests/fuzz/fuzz_entries.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace alloy::fuzz {

namespace fs = std::filesystem;

namespace {

/// The scratch folder of the CLI target: a small scene, a mod with a runtime,
/// a broken scene. Rewritten for every input, with everything a run wrote.
const fs::path& cli_folder_fresh() {
  static fs::path dir;
  dir = fresh_folder("cli");
  write_file(dir / "tiny.lua",
             "world { dt = 1 / 100, seconds = 0.1, report = { \"ball.position.y@0.05\" } }\n"
             "object { name = \"ball\", position = { 0, 1 }, shape = \"sphere\", radius = 0.1, "
             "mass = 1 }\n");
  write_file(dir / "bad.lua", "world { dt = -1 }\nobject { name = 3 }\n");
  write_file(dir / "tinymod" / "mod.lua",
             "return { name = \"tinymod\", version = \"1\", runtime = \"runtime.lua\", scene = "
             "\"scene.lua\" }\n");
  write_file(dir / "tinymod" / "runtime.lua",
             "mod.property { name = \"glow\" }\n"
             "mod.interaction { name = \"rigid_body_from_glow\", reads = { \"glow\" }, needs = { "
             "\"glow\" },\n"
             "  target = \"rigid_body\", apply = function(w)\n"
             "    for i in w:each(\"glow\") do w.target.add_force(i, vec3(0, 1, 0)) end end }\n"
             "mod.on(\"*\", function(e, state) print(e.type) end)\n");
  write_file(dir / "tinymod" / "scene.lua",
             "world { dt = 1 / 100, seconds = 0.1 }\n"
             "object { name = \"lamp\", position = { 0, 1 }, shape = \"sphere\", radius = 0.1, "
             "mass = 1, glow = 1 }\n");
  return dir;
}

}  // namespace

bool cli_arguments_allowed(std::string_view text) {
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string line(text.substr(pos, end - pos));
    pos = end + 1;
    // Paths stay in the scratch folder; the viewer needs a display; --watch
    // runs until interrupted.
    if (line.find('/') != std::string::npos || line.find("..") != std::string::npos) return false;
    if (line == "view" || line.find("watch") != std::string::npos) return false;
    // Every number that can be read anywhere in the argument (as CLI11 or
    // std::stod might: decimal, hex, exponent, inside a longer word) is small
    // and not tiny, so no run takes more than a couple of thousand steps.
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char* start = line.c_str() + i;
      char* stop = nullptr;
      const double v = std::strtod(start, &stop);
      if (stop == start) continue;
      if (std::isinf(v) || std::fabs(v) > 20 || (v != 0 && std::fabs(v) < 1e-2)) return false;
    }
  }
  return true;
}

void cli(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (size > 2000 || !cli_arguments_allowed(text)) return;
  std::vector<std::string> args{"alloy"};
  std::size_t pos = 0;
  while (pos <= text.size() && args.size() < 32) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    args.emplace_back(text.substr(pos, end - pos));
    pos = end + 1;
  }
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  argv.push_back(nullptr);

  const fs::path& dir = cli_folder_fresh();
  const fs::path before = fs::current_path();
  fs::current_path(dir);
  std::ostringstream out, err;
  guarded([&] { alloy::app::run_cli(int(args.size()), argv.data(), out, err); });
  fs::current_path(before);
}

}  // namespace alloy::fuzz
