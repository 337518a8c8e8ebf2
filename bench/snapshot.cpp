// What a snapshot costs (issue 14, item 5): time and bytes per body of a full
// snapshot, a delta snapshot one step after its base, a restore (which
// rebuilds every stage from the properties), and a state hash, on a pile of
// 1,000 and of 10,000 boxes falling into a bin (tests/scenes, the same pile as
// alloy_bench_rigid). The pile is let fall for a few steps first, so that
// every box moves between the base and the delta.
//
//   build/bench/alloy_bench_snapshot [--quick]
//
// Prints a Markdown table (docs/performance.md, "Snapshots"). Times are
// wall-clock medians of several repetitions, on whatever else the machine
// is doing: compare rows of one run, not runs.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <vector>

#include "bench/snapshot_pile.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/packed_delta.hpp"
#include "runtime/state_hash.hpp"
#include "runtime/world.hpp"

namespace {

using namespace alloy;

using bench::median_ms;

void row(int boxes, int reps) {
  bench::FallingPile pile(boxes);
  World& w = pile.world;
  const double bodies = double(w.store().object_count());

  Snapshot full;
  const double full_ms = median_ms(reps, [&] { full = w.snapshot(); });
  const Snapshot::Size full_size = full.size();
  w.step();
  Snapshot delta;
  const double delta_ms = median_ms(reps, [&] { delta = w.snapshot(&full); });
  const Snapshot::Size delta_size = delta.size(&full);
  // The packed delta (runtime/packed_delta.hpp): the delta snapshot, then
  // packed against its base; timed together, as a frame would take it.
  PackedDelta packed;
  const double packed_ms = median_ms(reps, [&] { packed = pack_delta(full, w.snapshot(&full)); });
  const double packed_bytes = double(packed.bytes(full)) / bodies;
  Snapshot unpacked;
  const double unpack_ms = median_ms(reps, [&] { unpacked = unpack_delta(full, packed); });
  if (hash_state(unpacked).world != hash_state(delta).world)
    std::fprintf(stderr, "%d boxes: the unpacked delta differs from the delta\n", boxes);
  std::uint64_t sink = 0;
  const double hash_ms = median_ms(reps, [&] { sink ^= hash_state(w).world; });
  const double restore_ms = median_ms(std::max(1, reps / 4), [&] { w.restore(full); });
  // The restore gives back the snapshot's properties, except what the
  // stages' rebuild writes (named on standard error: state a stage keeps
  // outside properties, docs/saves.md).
  for (const auto& d : hash_differences(hash_state(full), hash_state(w)))
    std::fprintf(stderr, "%d boxes: after restore, differs from the snapshot in %s\n", boxes,
                 d.c_str());
  const double restore_packed_ms =
      median_ms(std::max(1, reps / 4), [&] { w.restore(unpack_delta(full, packed)); });
  // Issue 14's goal: a delta of 1,000 moving boxes in at most 0.1 ms and 100
  // bytes a body; for other counts, 0.1 ms per 1,000 bodies.
  const bool goal = packed_ms <= 0.1 * bodies / 1000 && packed_bytes <= 100;
  std::printf(
      "| %d | %.0f | %.3f | %.0f | %.3f | %.0f (%zu of %zu columns shared) | %.3f | %.0f | %s "
      "| %.3f | %.3f | %.2f | %.2f |\n",
      boxes, bodies, full_ms, double(full_size.bytes) / bodies, delta_ms,
      double(delta_size.own_bytes()) / bodies, delta_size.shared_columns, delta_size.columns,
      packed_ms, packed_bytes, goal ? "pass" : "miss", unpack_ms, hash_ms, restore_ms,
      restore_packed_ms);
  (void)sink;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  std::printf(
      "| boxes | objects | full snapshot ms | full bytes/object | delta ms | delta bytes/object "
      "| packed delta ms | packed bytes/object | goal (<= 0.1 ms a 1,000, <= 100 B) | unpack ms "
      "| state hash ms | restore ms (rebuilds every stage) | restore from packed ms |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  row(1'000, quick ? 3 : 21);
  if (!quick) row(10'000, 9);
  return 0;
}
