#include "lua/memory_budget.hpp"

#include <cstdlib>

namespace alloy::lua {

void* MemoryBudget::allocate(void* ud, void* ptr, std::size_t old_size,
                             std::size_t new_size) noexcept {
  auto* self = static_cast<MemoryBudget*>(ud);
  // Lua passes old_size = 0 semantics only for fresh blocks when ptr is null.
  const std::size_t old_bytes = ptr ? old_size : 0;
  if (new_size == 0) {
    std::free(ptr);
    self->used_ -= old_bytes;
    return nullptr;
  }
  if (self->limit_ != 0 && new_size > old_bytes &&
      self->used_ - old_bytes + new_size > self->limit_ + self->slack_) {
    ++self->refusals_;
    // The error Lua raises can be caught; the tick that follows cannot.
    if (self->zero_on_refusal_) *self->zero_on_refusal_ = 0;
    return nullptr;  // Lua raises LUA_ERRMEM; a shrink is never refused (Lua requires it)
  }
  void* block = std::realloc(ptr, new_size);
  if (!block) return nullptr;
  self->used_ = self->used_ - old_bytes + new_size;
  if (self->used_ > self->peak_) self->peak_ = self->used_;
  return block;
}

}  // namespace alloy::lua
