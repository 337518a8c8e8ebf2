// State kept outside the world that a snapshot must carry all the same: the
// mods' `state` tables, which live in each mod's Lua state (lua::ModRuntime).
//
// runtime/ knows nothing of Lua, so the owner of such state registers a pair
// of callbacks with the world (World::add_state_owner). World::snapshot calls
// `save`; World::restore calls `prepare` after its own checks and before it
// changes anything, and the function `prepare` returns once the world is
// committed to the restore. A restore is thus a transaction for the owner
// too: everything that can fail (reading the bytes, a mod that is missing, a
// migration that raises or runs out of budget) fails in `prepare`, while the
// world and the owner's current state are still untouched.
#pragma once

#include <functional>

#include "runtime/snapshot.hpp"

namespace alloy {

struct StateOwner {
  /// Adds what the owner keeps to `out` (Snapshot::mod_states), between
  /// steps. Throws InputError for state that cannot be saved (the message
  /// names the mod and what is wrong); the snapshot is then not taken.
  std::function<void(Snapshot& out)> save;
  /// Reads and checks what the owner keeps in `in`, and prepares its new
  /// state, changing nothing the world or the game sees. Throws InputError.
  /// Returns the commit: called at most once, when the world has accepted
  /// the snapshot and before it rebuilds its stages (they see the restored
  /// state); it must not throw. Dropping it uncalled discards the
  /// preparation (a later check of the restore failed). An empty function:
  /// nothing to commit.
  std::function<std::function<void()>(const Snapshot& in)> prepare;
};

}  // namespace alloy
