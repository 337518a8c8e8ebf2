// What a mod's `state` table costs a snapshot (lua/state_codec.hpp): CPU
// time to encode it and to check and decode it, and its bytes, for a few
// state shapes. Prints a Markdown table (docs/modding.md, "Mod state and
// migrations"):   build/bench/alloy_bench_mod_state
#include <time.h>

#include <cstdio>
#include <lua.hpp>
#include <string>
#include <vector>

#include "lua/state_codec.hpp"

namespace {

double cpu_ms() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) / 1e6;
}

}  // namespace

int main() {
  using namespace alloy::lua;
  lua_State* L = luaL_newstate();
  luaL_openlibs(L);
  const char* cases[][2] = {
      {"a few keys (magic: {flights = n})", "return { flights = 3 }"},
      {"250 records of 3 fields (1,000 entries)",
       "local t = {} for i = 0, 249 do t[i] = { mana = i / 3, seen = i % 2 == 0, "
       "name = 'stone' .. i } end return { stones = t }"},
      {"a list of 10,000 numbers",
       "local t = {} for i = 1, 10000 do t[i] = i / 7 end return { list = t }"},
      {"a list of 100,000 numbers",
       "local t = {} for i = 1, 100000 do t[i] = i / 7 end return { list = t }"},
  };
  std::printf("| state | bytes | encode, ms | check + decode, ms |\n| --- | --- | --- | --- |\n");
  for (const auto& c : cases) {
    if (luaL_dostring(L, c[1]) != 0) return 1;
    const int n = 50;
    std::vector<std::byte> b;
    const double t0 = cpu_ms();
    for (int i = 0; i < n; ++i) b = encode_state(L, -1, "m", {});
    const double t1 = cpu_ms();
    for (int i = 0; i < n; ++i) {
      check_state(b, "m", {});
      std::string error;
      if (!decode_state(L, b, &error)) return 1;
      lua_pop(L, 1);
    }
    const double t2 = cpu_ms();
    std::printf("| %s | %zu | %.4f | %.4f |\n", c[0], b.size(), (t1 - t0) / n, (t2 - t1) / n);
    lua_pop(L, 1);
  }
  lua_close(L);
}
