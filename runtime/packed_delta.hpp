// A packed delta snapshot (issue 14, item 5): what changed since a base
// snapshot of the same world, in few bytes, for rollback and undo every frame.
//
// World::snapshot(&base) already shares every column that did not change with
// the base; a column in which one value moved is still copied whole, and the
// object table always is. pack_delta goes further:
//   - a changed column of 8-byte words (number, vec3, quat, int) whose
//     presence flags did not change is stored as each word XORed with the
//     base's, without its leading zero bytes (a value that moved a little
//     keeps its sign, exponent and high mantissa bits: those XOR to zero),
//     with a 4-bit count of the bytes kept per word;
//   - the object table and the slots' areas are dropped when equal to the
//     base's;
//   - everything else (other columns, stage states, schedule) is kept as the
//     snapshot holds it.
// unpack_delta(base, packed) gives back the snapshot, bit for bit.
#pragma once

#include <cstddef>
#include <vector>

#include "runtime/snapshot.hpp"

namespace alloy {

struct PackedDelta {
  /// The snapshot without what is packed or equal to the base: packed
  /// columns have null values, and the object table and areas are empty when
  /// `same_objects` / `same_areas`.
  Snapshot rest;
  bool same_objects = false;
  bool same_areas = false;
  /// Per packed column (in `rest.columns` order, those with null values):
  /// the 4-bit byte counts, two per byte, then the kept bytes.
  std::vector<std::vector<std::byte>> packed;
  /// Bytes this delta holds of its own (not shared with the base).
  std::size_t bytes(const Snapshot& base) const;
};

/// Packs `snapshot` against `base` (both taken from one world, `snapshot`
/// with World::snapshot(&base) or without).
PackedDelta pack_delta(const Snapshot& base, const Snapshot& snapshot);
/// The snapshot `pack_delta(base, s)` was made of, bit for bit. Throws
/// InputError if `packed` does not fit `base`.
Snapshot unpack_delta(const Snapshot& base, const PackedDelta& packed);

}  // namespace alloy
