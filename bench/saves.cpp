// What save files and replays cost (issue 14, items 2 and 3):
//
//   save      a full save of the doorbell after 1 s (goal: under 50 KB), and of
//             a pile of 1,000 boxes: bytes on disk (zstd) and before
//             compression, time to encode (snapshot + sections + zstd +
//             checksum) and to decode and restore;
//   replay    the doorbell run for 2 s plain, recorded (a state hash, object
//             hashes and per-stage hashes every step), and replayed
//             (runtime/replay.hpp): the time of each against the plain run.
//
//   build/bench/alloy_bench_saves [--quick]
//
// Prints Markdown tables (docs/saves.md, "Cost"); exits 1 if the doorbell's
// save misses its 50 KB goal. Times are wall-clock medians on whatever else
// the machine is doing: compare rows of one run, not runs.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <optional>
#include <vector>

#include "bench/snapshot_pile.hpp"
#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/replay.hpp"
#include "runtime/save_file.hpp"
#include "runtime/world.hpp"

namespace {

using namespace alloy;

using bench::median_cpu_ms;
using bench::median_ms;

struct Scene {
  Scene() {
    register_native_plugins(registry);
    loaded = lua::load_scene(std::string(ALLOY_SOURCE_DIR) + "/mods/doorbell", registry);
  }
  World& world() { return *loaded.world; }
  PluginRegistry registry;
  lua::LoadedScene loaded;
};

SaveMeta meta(World& w) {
  SaveMeta m = describe_world(w);
  m.scene = std::string(ALLOY_SOURCE_DIR) + "/mods/doorbell";
  m.scene_name = "doorbell";
  m.mods = {{"doorbell", "0.1.0"}};
  return m;
}

/// One row of the save table; returns the bytes on disk.
std::size_t save_row(const char* what, World& w, const SaveMeta& m, int reps,
                     const std::function<World&()>& fresh) {
  SaveData d;
  d.meta = m;
  std::string bytes;
  const double encode_ms = median_ms(reps, [&] {
    d.snapshot = w.snapshot();
    bytes = encode_save(d);
  });
  const std::size_t raw =
      unpack_save(bytes, "bench").body.size() + unpack_save(bytes, "bench").meta.size();
  World& target = fresh();
  const double decode_ms = median_ms(reps, [&] { (void)decode_save(bytes, "bench"); });
  const double restore_ms = median_ms(
      std::max(1, reps / 4), [&] { target.restore(decode_save(bytes, "bench").snapshot); });
  // Where the encode goes, in CPU time: the snapshot, the sections, zstd
  // with the checksum.
  const double encode_cpu = median_cpu_ms(reps, [&] {
    d.snapshot = w.snapshot();
    bytes = encode_save(d);
  });
  const double snapshot_cpu = median_cpu_ms(reps, [&] { d.snapshot = w.snapshot(); });
  const SaveContainer container = unpack_save(bytes, "bench");
  const double pack_cpu = median_cpu_ms(reps, [&] { (void)pack_save(container); });
  std::fprintf(stderr,
               "%s: encode %.3f ms CPU = snapshot %.3f + sections %.3f + zstd and checksum %.3f\n",
               what, encode_cpu, snapshot_cpu, encode_cpu - snapshot_cpu - pack_cpu, pack_cpu);
  const double objects = double(w.store().object_count());
  std::printf("| %s | %.0f | %zu | %.0f | %zu | %.3f | %.3f | %.2f |\n", what, objects,
              bytes.size(), double(bytes.size()) / objects, raw, encode_ms, decode_ms, restore_ms);
  return bytes.size();
}

double seconds_of(const std::function<void()>& f) {
  const auto a = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int reps = quick ? 3 : 15;
  std::printf(
      "| world | objects | bytes on disk | bytes/object | bytes before zstd | encode ms | "
      "decode ms | decode + restore ms |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
  std::size_t doorbell_bytes = 0;
  {
    Scene s;
    s.world().run(240);
    std::optional<Scene> other;
    doorbell_bytes = save_row("doorbell after 1 s", s.world(), meta(s.world()), reps,
                              [&]() -> World& { return other.emplace().world(); });
  }
  {
    bench::FallingPile pile(1000);
    SaveMeta m = describe_world(pile.world);
    m.scene = "(built in C++)";
    std::optional<World> other;
    save_row("1,000 boxes falling", pile.world, m, reps, [&]() -> World& {
      other.reset();
      other.emplace(pile.registry, bench::FallingPile::def());
      bench::FallingPile::build_fresh(*other, 1000);
      return *other;
    });
  }

  // Replay verification speed against the run's own.
  const std::uint64_t steps = quick ? 120 : 480;
  double plain = 0, recorded = 0, replayed = 0;
  SaveData rec;
  {
    Scene s;
    plain = seconds_of([&] { s.world().run(steps); });
  }
  {
    Scene s;
    Recorder r(s.world(), meta(s.world()));
    recorded = seconds_of([&] { s.world().run(steps); });  // the recorder hears each step
    rec = decode_save(encode_save(r.data()), "bench");
  }
  std::optional<Scene> scene;
  ReplayResult result;
  replayed = seconds_of([&] {
    result = replay(rec, [&]() -> World& {
      scene.reset();
      return scene.emplace().world();
    });
  });
  const std::size_t rec_bytes = encode_save(rec).size();
  std::printf("\n| doorbell, %llu steps | seconds | steps/s | against the plain run |\n",
              (unsigned long long)steps);
  std::printf("| --- | --- | --- | --- |\n");
  std::printf("| run | %.3f | %.0f | 1.00 |\n", plain, double(steps) / plain);
  std::printf("| run, recorded | %.3f | %.0f | %.2f |\n", recorded, double(steps) / recorded,
              recorded / plain);
  std::printf("| replay (verify every step) | %.3f | %.0f | %.2f |\n", replayed,
              double(steps) / replayed, replayed / plain);
  std::printf("\nrecording: %zu bytes (%.0f bytes/step); replay: %s\n", rec_bytes,
              double(rec_bytes) / double(steps), result.message().c_str());
  std::printf("goal (a full save of the doorbell under 50 KB): %zu bytes, %s\n", doorbell_bytes,
              doorbell_bytes < 50 * 1024 ? "pass" : "miss");
  std::printf("replay verification: %.2f times the plain run's time (no goal: reported)\n",
              replayed / plain);
  if (doorbell_bytes >= 50 * 1024) {
    std::printf("goal missed: a full save of the doorbell takes %zu bytes, over 50 KB\n",
                doorbell_bytes);
    return 1;
  }
  if (!result.identical) return 1;
  return 0;
}
