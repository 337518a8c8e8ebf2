// The objects a stage acts on. A global stage acts on every object; a stage
// that belongs to an area (a planet, an orbit, a magic zone) acts only on the
// objects in that area. Views and writers handed to a scoped stage see only
// its scope: members() lists only objects in it, and a writer refuses any
// other object. Stages need no code of their own for areas.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/property_store.hpp"

namespace alloy {

class Scope {
 public:
  /// Whether the object in `slot` is in this scope.
  bool contains(std::uint32_t slot) const { return slot < in_.size() && in_[slot]; }
  /// Slots in this scope, ascending.
  std::span<const std::uint32_t> slots() const { return slots_; }
  /// Moves whenever an object enters or leaves.
  std::uint64_t version() const { return version_; }
  /// The members of `column` that are in this scope, ascending. Cached until
  /// the column's membership or the scope changes.
  std::span<const std::uint32_t> members_of(const ColumnBase& column) const;

 private:
  friend class World;
  struct Cached {
    std::uint64_t membership = ~0ull, scope = ~0ull;
    std::vector<std::uint32_t> slots;
  };
  std::vector<std::uint8_t> in_;
  std::vector<std::uint32_t> slots_;
  std::uint64_t version_ = 0;
  mutable std::vector<Cached> cache_;  // by property id
};

inline std::span<const std::uint32_t> Scope::members_of(const ColumnBase& column) const {
  if (cache_.size() <= column.id()) cache_.resize(column.id() + 1);
  Cached& c = cache_[column.id()];
  if (c.membership != column.membership_version() || c.scope != version_) {
    c.slots.clear();
    for (std::uint32_t s : column.members())
      if (contains(s)) c.slots.push_back(s);
    c.membership = column.membership_version();
    c.scope = version_;
  }
  return c.slots;
}

}  // namespace alloy
