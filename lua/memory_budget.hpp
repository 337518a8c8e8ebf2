// The allocator of a Lua state: counts what the state holds and refuses to go
// past a limit, so that a mod from a player cannot take the machine's memory.
// Lua turns a refused allocation into a catchable "not enough memory" error;
// nothing crashes and the host stays usable.
#pragma once

#include <cstddef>

namespace alloy::lua {

class MemoryBudget {
 public:
  /// limit_bytes = 0: no limit.
  explicit MemoryBudget(std::size_t limit_bytes = 0) : limit_(limit_bytes) {}

  std::size_t used() const { return used_; }
  std::size_t peak() const { return peak_; }
  std::size_t limit() const { return limit_; }
  void set_limit(std::size_t limit_bytes) { limit_ = limit_bytes; }
  /// Allocations refused because of the limit.
  std::size_t refusals() const { return refusals_; }

  /// A lua_Alloc: `ud` is the MemoryBudget. noexcept: it is called from inside
  /// the Lua VM, which must never see a C++ exception.
  static void* allocate(void* ud, void* ptr, std::size_t old_size, std::size_t new_size) noexcept;

 private:
  std::size_t limit_ = 0;
  std::size_t used_ = 0;
  std::size_t peak_ = 0;
  std::size_t refusals_ = 0;
};

}  // namespace alloy::lua
