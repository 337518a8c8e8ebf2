// The sandbox and the host: what a script can and cannot reach, errors that
// keep their place, a memory budget that holds, a stack that stays balanced.
#include "lua/sandbox.hpp"

#include <gtest/gtest.h>

#include <lua.hpp>
#include <stdexcept>
#include <string>

#include "lua/alloy_api.hpp"
#include "lua/lua_bridge.hpp"
#include "lua/lua_host.hpp"

namespace alloy::lua {
namespace {

class SandboxTest : public ::testing::Test {
 protected:
  /// Pushes a fresh sandbox environment with the alloy table.
  void push_env() {
    push_environment(L);
    push_alloy_api(L);
    lua_setfield(L, -2, "alloy");
  }

  /// Runs `code` in a fresh environment (or the one at `env`, if given) and
  /// returns its first result as text.
  std::string run(const std::string& code, int env = 0) {
    host.load_string(code, "sandbox_test.lua");
    if (env)
      lua_pushvalue(L, env);
    else
      push_env();
    lua_setfenv(L, -2);
    host.call(0, 1, ErrorLocation{"sandbox_test.lua", 0, ""});
    std::string out;
    switch (lua_type(L, -1)) {
      case LUA_TNIL:
        out = "nil";
        break;
      case LUA_TBOOLEAN:
        out = lua_toboolean(L, -1) ? "true" : "false";
        break;
      default:
        out = lua_tostring(L, -1) ? lua_tostring(L, -1) : luaL_typename(L, -1);
    }
    lua_pop(L, 1);
    return out;
  }

  LuaHost host;
  lua_State* L = host.state();
};

TEST_F(SandboxTest, HostLibrariesAndUnsafeFunctionsAreAbsent) {
  for (const char* name :
       {"io", "os", "debug", "ffi", "jit", "package", "dofile", "loadfile", "loadstring", "getfenv",
        "setfenv", "collectgarbage", "newproxy", "module", "gcinfo", "require"}) {
    EXPECT_EQ(run(std::string("return type(") + name + ")"), "nil") << name;
  }
  EXPECT_EQ(lua_gettop(L), 0);
}

TEST_F(SandboxTest, SafeLibrariesArePresent) {
  EXPECT_EQ(run("return string.format('%d-%s', 3, string.upper('x'))"), "3-X");
  EXPECT_EQ(run("return table.concat({1, 2, 3}, ',')"), "1,2,3");
  EXPECT_EQ(run("return math.floor(math.pi)"), "3");
  EXPECT_EQ(run("return bit.band(6, 3)"), "2");
  EXPECT_EQ(run("local co = coroutine.wrap(function() coroutine.yield(7) end) return co()"), "7");
  EXPECT_EQ(run("local ok, e = pcall(error, 'x', 0) return tostring(ok) .. e"), "falsex");
}

TEST_F(SandboxTest, StringDumpIsUnreachable) {
  EXPECT_EQ(run("return type(string.dump)"), "nil");
  EXPECT_EQ(run("return type(('').dump)"), "nil");
  // The string metatable (whose __index is the real string table) is hidden.
  EXPECT_EQ(run("return tostring(getmetatable(''))"), "false");
}

TEST_F(SandboxTest, LoadCompilesTextIntoTheCallersEnvironment) {
  EXPECT_EQ(run("x = 41 return load('return x + 1')()"), "42");
  EXPECT_EQ(run("local f = load('return y', 'chunk', 't', { y = 'given' }) return f()"), "given");
  EXPECT_EQ(
      run("local f, err = load('return +') return tostring(f) .. ' ' .. tostring(err ~= nil)"),
      "nil true");
}

TEST_F(SandboxTest, LoadRefusesBytecode) {
  // Make real bytecode with a separate, unsandboxed state.
  lua_State* raw = luaL_newstate();
  luaL_openlibs(raw);
  ASSERT_EQ(luaL_dostring(raw, "return string.dump(function() return 1 end)"), 0);
  std::size_t n = 0;
  const char* bytes = lua_tolstring(raw, -1, &n);
  const std::string bytecode(bytes, n);
  lua_close(raw);

  push_env();
  const int env = lua_gettop(L);
  lua_pushlstring(L, bytecode.data(), bytecode.size());
  lua_setfield(L, env, "blob");
  EXPECT_EQ(run("local f, err = load(blob) return tostring(f)", env), "nil");
  EXPECT_EQ(run("local ok = pcall(load, blob, 'b', 'b') return ok", env), "false");
  EXPECT_EQ(run("local ok = pcall(load, blob, 'bt', 'bt') return ok", env), "false");
  lua_pop(L, 1);

  // Nor can a host file be bytecode.
  EXPECT_THROW(host.load_string(bytecode, "compiled.lua"), InputError);
  EXPECT_EQ(lua_gettop(L), 0);
}

TEST_F(SandboxTest, HostTablesAreReadOnly) {
  EXPECT_EQ(run("return (pcall(function() alloy.version = 'x' end))"), "false");
  EXPECT_EQ(run("return (pcall(rawset, alloy, 'version', 'x'))"), "false");
  EXPECT_EQ(run("return (pcall(setmetatable, alloy, {}))"), "false");
  EXPECT_EQ(run("return alloy.version"), "0.1.0");
  // rawset still works on the script's own tables.
  EXPECT_EQ(run("local t = {} rawset(t, 'k', 5) return t.k"), "5");
  // A script's frozen table is a host table too.
  EXPECT_EQ(
      run("local t = alloy.freeze({ a = 1 }) return tostring(pcall(rawset, t, 'a', 2)) .. t.a"),
      "false1");
}

TEST_F(SandboxTest, EachEnvironmentHasItsOwnLibraries) {
  push_env();
  const int first = lua_gettop(L);
  push_env();
  const int second = lua_gettop(L);
  run("string.upper = function() return 'hijacked' end x = 1", first);
  EXPECT_EQ(run("return string.upper('a')", first), "hijacked");
  EXPECT_EQ(run("return string.upper('a') .. tostring(x)", second), "Anil");
  lua_pop(L, 2);
}

TEST_F(SandboxTest, RuntimeErrorsKeepFileLineAndTraceback) {
  try {
    run("local function f()\n  return nil + 1\nend\nreturn f()");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file, "sandbox_test.lua");
    EXPECT_EQ(e.where().line, 2);
    EXPECT_NE(std::string(e.what()).find("attempt to perform arithmetic"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("stack traceback"), std::string::npos) << e.what();
  }
  EXPECT_EQ(lua_gettop(L), 0);
}

TEST_F(SandboxTest, ErrorTablesCarryTheObject) {
  try {
    run("\nerror({ message = 'bad part', object = 'arm' }, 0)");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 2);
    EXPECT_EQ(e.where().object, "arm");
    EXPECT_EQ(e.bare(), "bad part");
  }
}

TEST_F(SandboxTest, SyntaxErrorsNameTheLine) {
  try {
    host.load_string("local a = 1\nlocal b = = 2\n", "broken.lua");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file, "broken.lua");
    EXPECT_EQ(e.where().line, 2);
  }
  EXPECT_EQ(lua_gettop(L), 0);
}

// A binding that throws: the exception must come out as a catchable Lua error.
int throwing_binding(lua_State* L) {
  return catch_exceptions(L, [&]() -> int {
    if (lua_toboolean(L, 1)) throw InputError(ErrorLocation{"", 0, "gear"}, "teeth must mesh");
    throw std::runtime_error("plain failure");
  });
}

TEST_F(SandboxTest, CppExceptionsBecomeLuaErrors) {
  push_env();
  const int env = lua_gettop(L);
  lua_pushcfunction(L, throwing_binding);
  lua_setfield(L, env, "boom");
  EXPECT_EQ(run("local ok, e = pcall(boom, false) return tostring(ok) .. ' ' .. tostring(e)", env),
            "false plain failure");
  EXPECT_EQ(run("local ok, e = pcall(boom, true) return e.object .. ': ' .. e.message", env),
            "gear: teeth must mesh");
  EXPECT_EQ(run("local ok, e = pcall(boom, true) return tostring(e)", env),
            "object 'gear': teeth must mesh");
  try {
    run("\n\nboom(true)", env);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 3);
    EXPECT_EQ(e.where().object, "gear");
  }
  lua_pop(L, 1);
  EXPECT_EQ(lua_gettop(L), 0);
}

TEST(SandboxMemory, TheBudgetStopsAGreedyScriptAndTheHostGoesOn) {
  LuaHost host(HostOptions{2u << 20});
  lua_State* L = host.state();
  host.load_string("local t = {} for i = 1, 1e8 do t[i] = {i} end", "greedy.lua");
  push_environment(L);
  lua_setfenv(L, -2);
  try {
    host.call(0, 0, ErrorLocation{"greedy.lua", 0, ""});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("memory"), std::string::npos) << e.what();
    EXPECT_EQ(e.where().file, "greedy.lua");
  }
  EXPECT_EQ(lua_gettop(L), 0);
  EXPECT_LE(host.memory().peak(), host.memory().limit());
  EXPECT_GT(host.memory().refusals(), 0u);

  // The state survives: a modest script runs afterwards.
  host.load_string("return 1 + 1", "after.lua");
  host.call(0, 1);
  EXPECT_EQ(lua_tointeger(L, -1), 2);
  lua_pop(L, 1);
}

TEST(SplitLocation, FindsTheChunkAndLine) {
  auto loc = split_location("mods/kit/init.lua:12: attempt to call a nil value");
  ASSERT_TRUE(loc);
  EXPECT_EQ(loc->chunk, "mods/kit/init.lua");
  EXPECT_EQ(loc->line, 12);
  EXPECT_EQ(loc->message, "attempt to call a nil value");
  EXPECT_FALSE(split_location("no location here: 12"));
}

}  // namespace
}  // namespace alloy::lua
