// The allocator of a Lua state: counts what the state holds and refuses to go
// past a limit, so that a mod from a player cannot take the machine's memory.
// Lua turns a refused allocation into a catchable "not enough memory" error;
// nothing crashes and the host stays usable. Catchable is not enough for a
// mod: a pcall would swallow the error and the mod would go on at the edge of
// its budget. So a refusal also zeroes the mod's budget tick counter
// (zero_on_refusal): the mod's next tick calls the host, which sees the
// refusal and stops the mod; once stopped every tick fails again.
#pragma once

#include <cstddef>
#include <cstdint>

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
  /// A counter set to 0 at every refusal (a mod's budget ticks, stage_abi.hpp),
  /// so that the mod's next tick reaches the host; nullptr: none. The counter
  /// must outlive the allocator's use of it.
  void zero_on_refusal(std::int16_t* counter) { zero_on_refusal_ = counter; }

  /// While one lives, the host is building values in the state for the mod
  /// (an event table before a handler runs, a stage's blocks before its first
  /// call): these run outside any protected call, where a refused allocation
  /// would be an unprotected error, so they may go past the limit by up to
  /// kHostReserve. The mod pays it back: its own next allocation past the
  /// limit is refused and stops it as usual.
  class HostScope {
   public:
    explicit HostScope(MemoryBudget& budget) : budget_(budget), saved_(budget.slack_) {
      budget_.slack_ = kHostReserve;
    }
    ~HostScope() { budget_.slack_ = saved_; }
    HostScope(const HostScope&) = delete;
    HostScope& operator=(const HostScope&) = delete;

   private:
    MemoryBudget& budget_;
    std::size_t saved_;
  };
  static constexpr std::size_t kHostReserve = 1u << 20;

  /// A lua_Alloc: `ud` is the MemoryBudget. noexcept: it is called from inside
  /// the Lua VM, which must never see a C++ exception.
  static void* allocate(void* ud, void* ptr, std::size_t old_size, std::size_t new_size) noexcept;

 private:
  std::size_t limit_ = 0;
  std::size_t used_ = 0;
  std::size_t peak_ = 0;
  std::size_t refusals_ = 0;
  std::int16_t* zero_on_refusal_ = nullptr;
  std::size_t slack_ = 0;  ///< kHostReserve while a HostScope lives, else 0
};

}  // namespace alloy::lua
