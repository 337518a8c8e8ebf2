// A mod's `state` table as bytes, and back (docs/modding.md, "Mod state and
// migrations"): what a snapshot and a save file hold of each mod.
//
// A state is a tree of plain data: numbers (every double, NaN and infinities
// included, kept bit for bit), strings (any bytes), booleans, and tables
// whose keys are strings or numbers. Object slots are numbers and stay valid
// because a snapshot keeps the object table; and the prelude's vec3 and quat
// values, kept as their doubles. Nothing else: no functions, coroutines,
// userdata or other cdata, no table with a metatable (its
// __pairs or __index would decide what is saved, and it would not come back),
// no table twice (a cycle, or one table under two keys: it would come back as
// two). The encoder reads tables raw: no code of the mod runs while it works.
//
// Format "alloy-mod-state-1" (host byte order, little endian on every
// platform alloy builds for):
//
//   state  := 0x01 table
//   value  := 'n' f64 | 's' u64 bytes | 't' | 'f' | table
//           | 'v' f64 f64 f64 (a vec3: x y z) | 'q' f64 f64 f64 f64 (a quat: w x y z)
//   table  := '{' u64 count (key value){count}
//   key    := 'n' f64 | 's' u64 bytes
//
// Keys are written in one order: numbers by value, then strings byte by byte
// (shorter first on a common prefix). Equal states give equal bytes, so the
// bytes can be hashed and compared. The decoder checks every byte before it
// makes a Lua value: a tag, a length past the end, keys out of order or
// repeated, a NaN key, a depth, a count or a size over the limits, bytes
// after the end are each an InputError naming the mod and the byte.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

struct lua_State;

namespace alloy::lua {

/// What one mod's state may take (ModBudget::state_*).
struct StateLimits {
  std::size_t bytes = 16u << 20;    ///< encoded size, all included
  std::size_t entries = 1'000'000;  ///< keys, over all its tables
  std::size_t depth = 64;           ///< tables nested in tables; the state itself is 1
};

inline constexpr std::uint8_t kStateFormat = 1;

/// Encodes the table at `index` of `L` (the state of mod `mod`). Throws
/// InputError "mod 'm': state.a[3].f is a function: ..." naming the key path
/// of the first value that is not allowed, or the limit passed. Leaves the
/// stack as it was. `cdata_parts`, if not 0, is the stack index of a
/// function that takes a cdata value and returns "vec3", x, y, z or "quat",
/// w, x, y, z (or nothing, for any other cdata): the prelude's, which runs
/// no code of the mod. Without it every cdata value is refused.
std::vector<std::byte> encode_state(lua_State* L, int index, const std::string& mod,
                                    const StateLimits& limits, int cdata_parts = 0);

/// Checks `bytes` whole, without Lua. Throws InputError naming `mod` and the
/// first byte that is wrong.
void check_state(const std::vector<std::byte>& bytes, const std::string& mod,
                 const StateLimits& limits);

/// Decodes: pushes the table `bytes` encode, which check_state accepted, in a
/// protected call: returns false with the Lua error in `error` (out of the
/// mod's memory) and pushes nothing.
/// `cdata_make`, the stack index of a function ("vec3", x, y, z) or ("quat",
/// w, x, y, z) -> value, is needed if the state holds any; without it they
/// come back as tables {x, y, z} and {w, x, y, z}.
bool decode_state(lua_State* L, const std::vector<std::byte>& bytes, std::string* error,
                  int cdata_make = 0);

}  // namespace alloy::lua
