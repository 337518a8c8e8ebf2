#include "lua/c_stack.hpp"

#include <pthread.h>

#include <lua.hpp>

namespace alloy::lua {

namespace {

thread_local const char* t_entry = nullptr;  // the outermost live CStackEntry
thread_local const char* t_low = nullptr;    // the lowest address of this thread's stack
thread_local bool t_low_known = false;

const char* frame() {
  return static_cast<const char*>(__builtin_frame_address(0));
}

const char* stack_low() {
  if (!t_low_known) {
    t_low_known = true;
    pthread_attr_t attr;
    if (pthread_getattr_np(pthread_self(), &attr) == 0) {
      void* addr = nullptr;
      std::size_t size = 0;
      if (pthread_attr_getstack(&attr, &addr, &size) == 0) t_low = static_cast<const char*>(addr);
      pthread_attr_destroy(&attr);
    }
  }
  return t_low;
}

}  // namespace

void check_c_stack(lua_State* L) {
  const char* here = frame();
  const char* low = stack_low();
  // The stack grows down on every platform alloy builds for (x86-64, arm64).
  const bool deep = t_entry && here < t_entry && std::size_t(t_entry - here) > kCStackLimit;
  const bool near_end = low && here > low && std::size_t(here - low) < kCStackReserve;
  if (deep || near_end)
    luaL_error(L,
               "C stack limit: calls nested too deeply through C functions (string.gsub, "
               "table.sort, tostring, string.format, coroutines, host functions)");
}

CStackEntry::CStackEntry() : previous_(t_entry) {
  // Only the outermost entry counts: a nested one (a manifest read while a
  // scene runs) must not give the script a fresh allowance.
  if (!t_entry) t_entry = frame();
  (void)stack_low();  // looked up once per thread, outside any script
}

CStackEntry::~CStackEntry() {
  t_entry = previous_;
}

}  // namespace alloy::lua
