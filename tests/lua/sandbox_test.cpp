// The sandbox and the host: what a script can and cannot reach, errors that
// keep their place, a memory budget that holds, a stack that stays balanced.
#include "lua/sandbox.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <lua.hpp>
#include <stdexcept>
#include <string>

#include "lua/alloy_api.hpp"
#include "lua/lua_bridge.hpp"
#include "lua/lua_host.hpp"
#include "lua/lua_patterns.hpp"

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

// --- the bounded pattern functions (lua_patterns.hpp) ----------------------------

// The differential test: LuaJIT's string.find, match, gmatch and gsub and the
// bounded ones side by side on the same calls, which must give the same
// results and the same errors. The calls are generated from a fixed seed
// (patterns built from items, quantifiers, captures, anchors, %b, %f and
// back-references, some malformed; short subjects over an alphabet that
// makes them match), plus hand-picked corner cases.
const char* kDifferential = R"LUA(
local bounded = ...
local seed = 12345
local function rnd(n) seed = (seed * 1103515245 + 12345) % 2147483648 return math.floor(seed / 65536) % n + 1 end
local function pick(t) return t[rnd(#t)] end

local atoms = { "a", "b", "c", "x", ".", "%a", "%d", "%s", "%w", "%x", "%p", "%l", "%u", "%c",
  "%z", "%g", "%A", "%S", "%D", "%W", "[abc]", "[^ab]", "[a-c]", "[%d_]", "[]a]", "[^%s]", "[a-]",
  "%%", "%.", "%(", "$", "^", " ", "1" }
local quants = { "", "", "", "*", "+", "-", "?" }
local function item()
  local r = rnd(20)
  if r == 1 then return "%b()" elseif r == 2 then return "%bab" elseif r == 3 then return "%f[%w]"
  elseif r == 4 then return "%f[%W]" elseif r == 5 then return "()" end
  return pick(atoms) .. pick(quants)
end
local malformed = { "[a", "%", "(", ")", "%b", "%ba", "%f", "%fa", "%1", "(a)%2", "((a)", "a)",
  "[%", "%0", "(()" }
local function pattern()
  if rnd(25) == 1 then return pick(malformed) end
  local parts, open = {}, 0
  if rnd(5) == 1 then parts[#parts + 1] = "^" end
  for _ = 1, rnd(5) do
    local r = rnd(8)
    if r == 1 and open < 3 then parts[#parts + 1] = "(" open = open + 1
    elseif r == 2 and open > 0 then parts[#parts + 1] = ")" open = open - 1
    elseif r == 3 and #parts > 0 and parts[1] ~= "^" and rnd(3) == 1 then parts[#parts + 1] = "%1"
    else parts[#parts + 1] = item() end
  end
  for _ = 1, open do parts[#parts + 1] = ")" end
  if rnd(6) == 1 then parts[#parts + 1] = "$" end
  return table.concat(parts)
end
local letters = { "a", "a", "b", "b", "c", "1", "2", " ", "_", "(", ")", "x", ".", "%", "A", "\0", "\n" }
local function subject()
  local t = {}
  for _ = 1, rnd(13) - 1 do t[#t + 1] = pick(letters) end
  return table.concat(t)
end

local function show(...)
  local t = { tostring(select("#", ...)) }
  for i = 1, select("#", ...) do
    local v = select(i, ...)
    t[#t + 1] = type(v) .. ":" .. tostring(v)
  end
  return table.concat(t, "|")
end
local function collect(gmatch, s, p)
  local ok, it = pcall(gmatch, s, p)
  if not ok then return show(false, it) end
  local out = {}
  for _ = 1, 50 do
    local r = { pcall(it) }
    out[#out + 1] = show(unpack(r))
    if not r[1] or r[2] == nil then break end
  end
  return table.concat(out, " ; ")
end

local calls, failures = 0, {}
local function same(what, a, b)
  calls = calls + 1
  if a ~= b and #failures < 10 then failures[#failures + 1] = what .. "\n  luajit:  " .. a .. "\n  bounded: " .. b end
end
local function fmt(s) return string.format("%q", s) end
local inits = { false, false, 1, 2, -1, -3, 0, 5, 20, -20 }
local repls = { "<%0>", "%1-%1", "%%", "x", "%2", "[%0%1]", "", 7, "a%" }
local tables = { a = "A", b = false, ["1"] = 9, ["("] = "P" }
local function fn(c, d) if c == "b" then return nil end return "{" .. tostring(c) .. tostring(d) .. "}" end

local function compare(s, p)
  local init = pick(inits) or nil
  local plain = rnd(6) == 1 or nil
  same("find(" .. fmt(s) .. ", " .. fmt(p) .. ", " .. tostring(init) .. ", " .. tostring(plain) .. ")",
       show(pcall(string.find, s, p, init, plain)), show(pcall(bounded.find, s, p, init, plain)))
  same("match(" .. fmt(s) .. ", " .. fmt(p) .. ", " .. tostring(init) .. ")",
       show(pcall(string.match, s, p, init)), show(pcall(bounded.match, s, p, init)))
  same("gmatch(" .. fmt(s) .. ", " .. fmt(p) .. ")", collect(string.gmatch, s, p), collect(bounded.gmatch, s, p))
  local r = rnd(3)
  local repl = r == 1 and pick(repls) or r == 2 and tables or fn
  local n = ({ nil, nil, 0, 1, 2 })[rnd(5)]
  same("gsub(" .. fmt(s) .. ", " .. fmt(p) .. ", " .. tostring(repl) .. ", " .. tostring(n) .. ")",
       show(pcall(string.gsub, s, p, repl, n)), show(pcall(bounded.gsub, s, p, repl, n)))
end

local fixed = {
  { "hello world", "o w" }, { "hello", "l+" }, { "key = value", "(%w+)%s*=%s*(%w+)" },
  { "f(a(b)c)d", "%b()" }, { "THE (quick) fox", "%f[%a]%a+" }, { "abcabc", "(abc)%1" },
  { "  trim  ", "^%s*(.-)%s*$" }, { "a.b.c", "%." }, { "a.b.c", "." }, { "", "" }, { "abc", "" },
  { "abc", "()" }, { "abc", "()b()" }, { "x=1, y=2", "(%w+)=(%w+)" }, { "aaa", "a-" },
  { "aaa", "^a-$" }, { "[x]", "[]]" }, { "a-b", "[a-]" }, { "a\0b", "%z" }, { "a\0b", "[%z]" },
  { "$5", "$5" }, { "5$", "5$" }, { "a^b", "a^b" }, { "THE END", "%u+" }, { "\t\n x", "%s+" },
  { "0x1F", "%x+" }, { "a,b;c", "%p" }, { "ab", "(a)(b)" }, { "ab", "((a)(b))" },
  { "abab", "(ab)*" }, { "aXb", "%f[%u]" }, { "hello", "(l)(l)" }, { "abc", "[^%a]" },
  { "abc", "a(" }, { "abc", "a)" }, { "abc", "[a" }, { "abc", "%" }, { "abc", "%g+" },
}
for _, c in ipairs(fixed) do compare(c[1], c[2]) end
for _ = 1, 700 do compare(subject(), pattern()) end
return calls, table.concat(failures, "\n")
)LUA";

TEST(BoundedPatterns, AgreeWithLuaJITsOwnOnGeneratedPatterns) {
  lua_State* L = luaL_newstate();
  luaL_openlibs(L);
  ASSERT_EQ(luaL_loadbuffer(L, kDifferential, std::strlen(kDifferential), "=differential"), 0)
      << lua_tostring(L, -1);
  lua_newtable(L);
  install_bounded_patterns(L, -1, nullptr);
  ASSERT_EQ(lua_pcall(L, 1, 2, 0), 0) << lua_tostring(L, -1);
  const int calls = int(lua_tointeger(L, -2));
  const std::string failures = lua_tostring(L, -1);
  lua_close(L);
  EXPECT_EQ(calls, 4 * (700 + 38));
  EXPECT_EQ(failures, "");
}

// The cost of the bounded matcher against LuaJIT's on ordinary patterns, run
// by hand (it measures time, so it is not part of the suite):
//   build/tests/lua/lua_tests --gtest_also_run_disabled_tests
//     --gtest_filter='BoundedPatterns.DISABLED_CostAgainstLuaJIT'
const char* kBenchmark = R"LUA(
local bounded, clock = ...
local text = ("The quick brown fox jumps over the lazy dog; key_%d = value %d, 12.5%%\n"):rep(20)
local cases = {
  { "find plain", "find", { "hello world, hello moon", "moon" } },
  { "find class", "find", { "hello world 42", "%d+" } },
  { "match pair", "match", { "key = value", "(%w+)%s*=%s*(%w+)" } },
  { "match trim", "match", { "   some text here   ", "^%s*(.-)%s*$" } },
  { "match number", "match", { "version 12.34 build", "(%d+)%.(%d+)" } },
  { "match date", "match", { "on 2026-11-25 at noon", "(%d+)-(%d+)-(%d+)" } },
  { "gsub spaces", "gsub", { text, "%s+", " " } },
  { "gsub function", "gsub", { text, "%a+", function(w) return nil end } },
  { "gsub table", "gsub", { text, "%%(%a)", { d = "1" } } },
  { "gmatch words", "gmatch", { text, "%a+" } },
}
local function run(lib, c, n)
  local f, a = lib[c[2]], c[3]
  if c[2] == "gmatch" then
    for _ = 1, n do for w in f(a[1], a[2]) do end end
  else
    for _ = 1, n do f(a[1], a[2], a[3]) end
  end
end
local out = {}
local total_j, total_b = 0, 0
for _, c in ipairs(cases) do
  local n = (c[2] == "gsub" or c[2] == "gmatch") and 2000 or 200000
  run(string, c, n / 10) run(bounded, c, n / 10)  -- warm up
  local t = clock() run(string, c, n) local tj = clock() - t
  t = clock() run(bounded, c, n) local tb = clock() - t
  total_j, total_b = total_j + tj, total_b + tb
  out[#out + 1] = (string.format("%-16s luajit %7.1f ns/call  bounded %7.1f ns/call  ratio %.2f", c[1], tj / n * 1e9, tb / n * 1e9, tb / tj))
end
out[#out + 1] = (string.format("%-16s ratio %.2f", "all", total_b / total_j))
return table.concat(out, "\n")
)LUA";

TEST(BoundedPatterns, DISABLED_CostAgainstLuaJIT) {
  lua_State* L = luaL_newstate();
  luaL_openlibs(L);
  ASSERT_EQ(luaL_loadbuffer(L, kBenchmark, std::strlen(kBenchmark), "=benchmark"), 0)
      << lua_tostring(L, -1);
  lua_newtable(L);
  install_bounded_patterns(L, -1, nullptr);
  lua_getglobal(L, "os");
  lua_getfield(L, -1, "clock");
  lua_remove(L, -2);
  ASSERT_EQ(lua_pcall(L, 2, 1, 0), 0) << lua_tostring(L, -1);
  std::printf("%s\n", lua_tostring(L, -1));
  lua_close(L);
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
