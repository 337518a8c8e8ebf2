// Determinism hashes: a 64-bit digest of everything that decides the world's
// next step, so that two runs can be compared by one number (`alloy run
// --hash`, the golden hashes in tests/runtime) and, when they differ, the
// part that differs can be named.
//
// Definition (version 1). Every hash is XXH3-64 (xxhash, seed 0) of a byte
// string. Integers and doubles are written as their exact bits in little-endian
// order (a double's IEEE-754 bits: -0.0 and 0.0 differ, every NaN payload
// counts); a string is its length (u64) then its bytes; an id is its index
// (u32) then its generation (u32). The parts, computed from a Snapshot:
//
//   column    per property column with at least one member: the property's
//             name, its kind (u8, PropertyKind), the member count (u64), then
//             for each member in ascending slot order: the slot (u32) and the
//             value (ColumnBase::encode: number f64; integer i64; bool u8;
//             vec3 x,y,z; quat w,x,y,z; string; ref id; reflist count (u64)
//             and ids; enum index i32). A column nobody carries is not
//             hashed, so a lookup that created an empty column changes nothing.
//   objects   slot count (u64); per slot its generation (u32), alive flag
//             (u8) and name; the free list: count (u64), slots (u32) in order.
//   schedule  step (u64), time (f64), dt (f64), started (u8), resync (u8); the pending
//             inputs: count, then each one's time, object id, property name,
//             value kind (u8, PropertyValue's index) and value; the pending
//             swaps: count, then each one's time, area, from, to.
//   stages    the active stage instances in run order (count, names); each
//             area's plugin list; the disabled and enabled plugin lists; the
//             `use` map in key order; the frozen object ids; the area of
//             each slot (i32); the stage states: count, then each one's
//             stage name and bytes (u64 length, bytes).
//   mod       per mod state of the snapshot (Snapshot::mod_states, in its
//             order): the mod's name, its version, the state's byte count
//             (u64) and bytes (lua/state_codec's encoding).
//   world     the tag "alloy-state-1", the objects, schedule and stages
//             hashes (u64 each), then the number of hashed columns (u64) and
//             for each, in property-name order (byte-wise), its name and hash;
//             then, only if at least one mod saved a state, the tag "mods",
//             the number of mod states (u64) and for each its name and hash
//             (so a world without mod state hashes as it did before).
//
// Not hashed: events already published, observers, profile timings, column
// change counters, the registry's definitions (units, docs, bounds), plugin
// settings and whatever of a mod's Lua state is outside its `state` table.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "runtime/object_id.hpp"
#include "runtime/snapshot.hpp"

namespace alloy {

class World;

struct StateHash {
  std::uint64_t world = 0;     ///< everything below, combined
  std::uint64_t objects = 0;   ///< the object table
  std::uint64_t schedule = 0;  ///< step, time, pending inputs and swaps
  std::uint64_t stages = 0;    ///< stage set, areas, frozen objects, stage states
  /// Per property with at least one member, in name order.
  std::vector<std::pair<std::string, std::uint64_t>> columns;
  /// Per stage that saved a state, in run order (also inside `stages`).
  std::vector<std::pair<std::string, std::uint64_t>> stage_states;
  /// Per mod that saved a state, in the snapshot's order (also inside `world`).
  std::vector<std::pair<std::string, std::uint64_t>> mod_states;
};

StateHash hash_state(const Snapshot& snapshot);
/// hash_state(world.snapshot()).
StateHash hash_state(const World& world);
/// The hash of one object: its id, name and, in property-name order, each
/// property it carries (name and value, encoded as in a column). Computed on
/// demand (it visits every column), to name the objects that differ.
std::uint64_t hash_object(const World& world, ObjectId id);
/// What differs between two hashes, one line each: "column 'position'",
/// "objects (ids, generations, names, free list)", "schedule (step, time,
/// pending inputs)", "stages (...)", "state of stage 'x'", "state of mod 'm'",
/// "column 'y' only in the first". Empty if the world hashes are equal.
std::vector<std::string> hash_differences(const StateHash& a, const StateHash& b);
/// 16 lower-case hex digits.
std::string hex(std::uint64_t hash);

}  // namespace alloy
