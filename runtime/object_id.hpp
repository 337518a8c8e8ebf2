// Generational object handles (Box2D's b2BodyId idea): an index into the
// property columns plus a generation that changes when the slot is reused, so
// a stale handle is detected instead of silently reading another object.
#pragma once

#include <compare>
#include <cstdint>
#include <functional>

namespace alloy {

struct ObjectId {
  static constexpr std::uint32_t kNoIndex = 0xffffffffu;
  /// Slot in every property column.
  std::uint32_t index = kNoIndex;
  /// Incremented each time the slot is freed; 0 is never a live generation.
  std::uint32_t generation = 0;

  constexpr bool is_null() const { return index == kNoIndex; }
  constexpr explicit operator bool() const { return !is_null(); }
  friend constexpr auto operator<=>(ObjectId, ObjectId) = default;
};

}  // namespace alloy

template <>
struct std::hash<alloy::ObjectId> {
  std::size_t operator()(alloy::ObjectId id) const noexcept {
    return (std::uint64_t(id.generation) << 32) ^ id.index;
  }
};
