#include "apps/viewer/palette.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>

#include "apps/viewer/scene_writer.hpp"

namespace alloy::viewer {

namespace fs = std::filesystem;

const std::vector<PaletteEntry>& palette_entries() {
  // One scale for every part, the electrical parts' (a 6 V lantern battery is
  // 11.5 cm long, a coil 5 cm): bars of 15 cm, disks of a few centimetres,
  // shelves of 30 cm, so that a lever, a hammer arm and a coil fit together
  // on the new board (1 m wide) without zooming.
  static const std::vector<PaletteEntry> entries = {
      {"steel bar", "bars", "steel_bar",
       R"(kit.bar { name = "$NAME", material = "steel", at = { $X, $Y }, length = 0.15, width = 0.01 })",
       "a 15 cm steel bar, 1 cm wide"},
      {"brass bar", "bars", "brass_bar",
       R"(kit.bar { name = "$NAME", material = "brass", at = { $X, $Y }, length = 0.15, width = 0.01 })",
       "a 15 cm brass bar, 1 cm wide"},
      {"copper bar", "bars", "copper_bar",
       R"(kit.bar { name = "$NAME", material = "copper", at = { $X, $Y }, length = 0.15, width = 0.01 })",
       "a 15 cm copper bar, 1 cm wide"},
      {"wooden plank", "bars", "plank",
       R"(kit.bar { name = "$NAME", material = "wood", at = { $X, $Y }, length = 0.25, width = 0.02 })",
       "a 25 cm wooden plank, 2 cm wide"},
      {"steel disk", "disks", "steel_disk",
       R"(kit.cylinder { name = "$NAME", material = "steel", at = { $X, $Y }, radius = 0.025 })",
       "r = 2.5 cm, 2 cm thick"},
      {"rubber ball", "disks", "ball",
       R"(kit.disk { name = "$NAME", material = "rubber", at = { $X, $Y }, radius = 0.02 })",
       "r = 2 cm, bouncy"},
      {"wooden wheel", "disks", "wheel",
       R"(kit.cylinder { name = "$NAME", material = "wood", at = { $X, $Y }, radius = 0.05, depth = 0.02 })",
       "r = 5 cm"},
      {"pinned wheel", "disks", "wheel",
       R"(kit.cylinder { name = "$NAME", material = "wood", at = { $X, $Y }, radius = 0.05, depth = 0.02 }
kit.pin { name = "$NAME_pin", part = "$NAME", friction = 0.02 })",
       "a wheel on a pin through its centre: it turns, and stays"},
      {"shelf", "fixed", "shelf",
       R"(kit.floor { name = "$NAME", at = { $X, $Y }, size = { 0.3, 0.02 } })",
       "a static wooden shelf, 30 cm"},
      {"ramp", "fixed", "ramp",
       R"(kit.floor { name = "$NAME", at = { $X, $Y }, size = { 0.3, 0.02 }, angle = -0.3 })",
       "a static 30 cm shelf tilted by 17 degrees"},
      {"post", "fixed", "post",
       R"(kit.floor { name = "$NAME", at = { $X, $Y }, size = { 0.02, 0.12 } })",
       "a static wooden post, 12 cm tall: a lever's support"},
      {"battery", "electric", "battery",
       R"(kit.battery { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "6 V, pinned; - at its left end, + at its right"},
      {"contact", "electric", "contact",
       R"(kit.contact { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "a brass contact block, pinned: touching parts connect through it"},
      {"coil", "electric", "coil", R"(kit.coil { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "an electromagnet on an iron core, pinned: 500 turns"},
      {"bell", "electric", "bell", R"(kit.bell { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "a bronze bell, pinned: it rings when struck"},
      // The circuit parts at their real sizes (a 5 W resistor is 2.2 cm, a
      // torch bulb 3 cm, a knife switch 6 cm): the battery's scale. Pinned,
      // so that a circuit laid out on the board stays where it was put.
      {"switch", "electric", "switch",
       R"(kit.switch { name = "$NAME", at = { $X, $Y }, pinned = true, closed = true })",
       "a knife switch, closed, pinned: click it to open or close it"},
      {"resistor", "electric", "resistor",
       R"(kit.resistor { name = "$NAME", at = { $X, $Y }, pinned = true })", "10 ohm, 5 W, pinned"},
      {"junction", "electric", "junction",
       R"(kit.junction { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "a brass terminal block, pinned: every wire ending on it meets at one node"},
      {"lamp", "electric", "lamp", R"(kit.lamp { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "a 6 V 0.5 A torch bulb (12 ohm), pinned: it glows with the power it takes"},
      {"capacitor", "electric", "capacitor",
       R"(kit.capacitor { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "10 mF electrolytic, pinned"},
      {"photocell", "electric", "photocell",
       R"(kit.photocell { name = "$NAME", at = { $X, $Y }, pinned = true })",
       "a light-dependent resistor, face up, pinned: 1 Mohm dark, less in light"},
      {"magnet", "magnetic", "magnet", R"(kit.magnet { name = "$NAME", at = { $X, $Y } })",
       "a neodymium bar magnet, north (red) at its right end"},
      {"armature", "magnetic", "armature",
       R"(kit.armature { name = "$NAME", at = { $X, $Y }, length = 0.05 })",
       "a soft-iron bar: magnets and coils pull on it"},
  };
  return entries;
}

namespace {

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t pos = 0; (pos = s.find(from, pos)) != std::string::npos; pos += to.size())
    s.replace(pos, from.size(), to);
  return s;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

/// Runs the entry as a scene and returns the scratch world.
lua::LoadedScene run_entry(PluginRegistry& registry, const PaletteEntry& entry, Vec2 at,
                           const lua::LoadOptions& options, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("alloy_view_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "palette_part.lua";
  std::string code = "local kit = require \"kit\"\n" + entry.lua + "\n";
  code = replace_all(code, "$NAME", name);
  code = replace_all(code, "$X", number(at.x));
  code = replace_all(code, "$Y", number(at.y));
  write_file_whole(file, code);
  return lua::load_scene(file, registry, options);
}

}  // namespace

std::vector<ObjectId> make_part(World& world, const PaletteEntry& entry, Vec2 at,
                                const lua::LoadOptions& options, const std::string& name) {
  lua::LoadedScene scratch = run_entry(world.plugins(), entry, at, options, name);
  const World& from = *scratch.world;
  const PropertyStore& src = from.store();
  const PropertyRegistry& reg = from.properties();
  const PropertyId name_id = reg.id("name");

  // Create them all first, so that references among them can be mapped.
  std::map<std::uint32_t, ObjectId> made;
  std::vector<ObjectId> out;
  try {
    for (std::uint32_t s = 0; s < src.slot_count(); ++s) {
      const ObjectId o = src.id_at(s);
      if (!o) continue;
      std::string n = src.has(o, name_id) ? std::get<std::string>(src.get(o, name_id)) : "";
      if (!n.empty() && world.find(n)) {
        for (int k = 2;; ++k)
          if (!world.find(n + "_" + std::to_string(k))) {
            n += "_" + std::to_string(k);
            break;
          }
      }
      made[s] = world.create(n);
      out.push_back(made[s]);
    }
    for (std::uint32_t s = 0; s < src.slot_count(); ++s) {
      const ObjectId o = src.id_at(s);
      if (!o) continue;
      for (PropertyId p = 0; p < reg.size(); ++p) {
        if (p == name_id || !src.has(o, p)) continue;
        PropertyValue v = src.get(o, p);
        if (ObjectId* r = std::get_if<ObjectId>(&v))
          *r = made.count(r->index) ? made[r->index] : ObjectId{};
        if (RefList* l = std::get_if<RefList>(&v))
          for (ObjectId& r : *l) r = made.count(r.index) ? made[r.index] : ObjectId{};
        world.set(made[s], p, v);
      }
    }
  } catch (...) {
    for (ObjectId id : out) world.destroy(id);
    throw;
  }
  // The part itself first: the object named as asked.
  std::stable_partition(out.begin(), out.end(),
                        [&](ObjectId id) { return world.describe(id) == name; });
  return out;
}

std::string check_entry(PluginRegistry& registry, const PaletteEntry& entry,
                        const lua::LoadOptions& options) {
  try {
    run_entry(registry, entry, {0, 0}, options, "probe");
    return "";
  } catch (const std::exception& e) {
    return e.what();
  }
}

}  // namespace alloy::viewer
