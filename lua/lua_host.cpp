#include "lua/lua_host.hpp"

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <lua.hpp>
#include <sstream>
#include <stdexcept>

#include "lua/budget_ticks.hpp"
#include "lua/c_stack.hpp"
#include "lua/sandbox.hpp"

namespace alloy::lua {

namespace {

// Lua calls this only for an error outside any protected call, which the host
// never makes on purpose. Throwing (rather than letting Lua abort the process)
// keeps the promise "never abort": LuaJIT on x64 unwinds C++ frames.
constexpr const char* kHostKey = "alloy.host";
constexpr int kCountStep = 10000;  // instructions between two budget checks
// Steps of C work collected before they are passed on: the budgets are
// checked at most once per quantum (a few microseconds of matching).
constexpr std::uint64_t kWorkQuantum = 4096;

int on_panic(lua_State* L) {
  const char* s = lua_tostring(L, -1);
  throw std::runtime_error(std::string("unprotected Lua error: ") + (s ? s : "?"));
}

std::string read_file(const std::filesystem::path& file, const std::string& display) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(ErrorLocation{display, 0, ""}, "cannot read the file");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

std::optional<LocatedMessage> split_location(std::string_view message) {
  // "chunk:12: rest", the prefix luaL_where and the parser put on messages.
  for (std::size_t i = 0; i < message.size(); ++i) {
    if (message[i] == '\n') break;
    if (message[i] != ':') continue;
    std::size_t j = i + 1;
    while (j < message.size() && message[j] >= '0' && message[j] <= '9') ++j;
    if (j == i + 1 || j + 1 >= message.size() || message[j] != ':' || message[j + 1] != ' ')
      continue;
    LocatedMessage out;
    out.chunk = std::string(message.substr(0, i));
    out.line = std::stoi(std::string(message.substr(i + 1, j - i - 1)));
    out.message = std::string(message.substr(j + 2));
    return out;
  }
  return std::nullopt;
}

LuaHost::LuaHost(HostOptions options)
    : budget_(std::make_unique<MemoryBudget>(options.memory_limit)),
      memory_limit_(options.memory_limit),
      instruction_limit_(options.instruction_limit),
      seconds_limit_(options.seconds_limit) {
  // The limit applies to scripts, not to setting the state up.
  budget_->set_limit(0);
  L_ = lua_newstate(&MemoryBudget::allocate, budget_.get());
  if (!L_) throw std::runtime_error("LuaJIT could not create a state with the alloy allocator");
  lua_atpanic(L_, on_panic);
  patterns_.steps_per_call = options.pattern_steps;
  patterns_.owner = this;
  patterns_.charge = [](void* host, lua_State* L, std::uint64_t steps) {
    static_cast<LuaHost*>(host)->charge_work(L, steps);
  };
  patterns_.refuse = [](void* owner, lua_State* L, const std::string& why) {
    auto* host = static_cast<LuaHost*>(owner);
    if (host->account_.refuse) host->account_.refuse(L, why);
    // No account: an error at the caller's line. The steps are charged, so
    // a script that catches it and tries again runs out of its budget.
    host->charge_work(L, host->patterns_.steps_per_call);
    luaL_error(L, "%s", why.c_str());
  };
  prepare_state(L_, &patterns_);
  lua_pushlightuserdata(L_, this);
  lua_setfield(L_, LUA_REGISTRYINDEX, kHostKey);
  // The message handler of call(), made once rather than on every call
  // (Lua stages are called every step).
  lua_pushlightuserdata(L_, this);
  lua_pushcclosure(L_, &LuaHost::on_error, 1);
  handler_ref_ = luaL_ref(L_, LUA_REGISTRYINDEX);
  if (instruction_limit_ > 0) {
    luaJIT_setmode(L_, 0, LUAJIT_MODE_ENGINE | LUAJIT_MODE_OFF);
    lua_sethook(L_, &LuaHost::on_count, LUA_MASKCOUNT, kCountStep);
  }
  budget_->set_limit(options.memory_limit == 0 ? 0 : budget_->used() + options.memory_limit);
}

LuaHost::~LuaHost() {
  if (L_) lua_close(L_);
}

LuaHost* LuaHost::from(lua_State* L) {
  lua_getfield(L, LUA_REGISTRYINDEX, kHostKey);
  auto* host = static_cast<LuaHost*>(lua_touserdata(L, -1));
  lua_pop(L, 1);
  return host;
}

void LuaHost::use_budget_ticks(int index) {
  lua_pushvalue(L_, index);
  if (ticks_ref_ != -2) luaL_unref(L_, LUA_REGISTRYINDEX, ticks_ref_);
  ticks_ref_ = luaL_ref(L_, LUA_REGISTRYINDEX);
}

bool LuaHost::compile(std::string_view code, const std::string& chunkname) {
  if (!code.empty() && code[0] == '\x1b') {  // LUA_SIGNATURE: bytecode, which can crash the VM
    lua_pushfstring(L_, "%s: attempt to load a binary chunk: only source text can be loaded",
                    chunkname.empty() ? "?" : chunkname.c_str() + 1);
    return false;
  }
  std::string ticked;
  if (ticks_ref_ != -2) {
    try {
      ticked = add_budget_ticks(code, chunkname.empty() ? "?" : chunkname.substr(1));
    } catch (const InputError& e) {
      const std::string msg =
          e.where().file + ":" + std::to_string(e.where().line) + ": " + e.bare();
      lua_pushlstring(L_, msg.data(), msg.size());
      return false;
    }
    code = ticked;
  }
  // Mode "t": text only. Precompiled bytecode can crash the VM and is refused.
  if (luaL_loadbufferx(L_, code.data(), code.size(), chunkname.c_str(), "t") != 0) return false;
  if (ticks_ref_ == -2) return true;
  // The instrumented chunk returns function(tick) return function(...) <code> end end:
  // two calls give the function that runs the code, with the tick as its upvalue.
  lua_rawgeti(L_, LUA_REGISTRYINDEX, ticks_ref_);
  lua_insert(L_, -2);
  if (lua_pcall(L_, 0, 1, 0) != 0) {  // only an allocation can fail here
    lua_remove(L_, -2);
    return false;
  }
  lua_insert(L_, -2);
  if (lua_pcall(L_, 1, 1, 0) != 0) return false;
  return true;
}

void LuaHost::load_string(std::string_view code, const std::string& display) {
  files_.insert(display);
  if (compile(code, "@" + display)) return;
  std::string message = lua_tostring(L_, -1) ? lua_tostring(L_, -1) : "cannot load the chunk";
  lua_pop(L_, 1);
  ErrorLocation where{display, 0, ""};
  if (auto loc = split_location(message)) {
    where.line = loc->line;
    message = loc->message;
  }
  throw InputError(where, message);
}

void LuaHost::load_file(const std::filesystem::path& file, const std::string& display) {
  load_string(read_file(file, display), display);
}

ErrorLocation LuaHost::user_location(lua_State* L) const {
  ErrorLocation innermost;
  lua_Debug ar;
  for (int level = 0; lua_getstack(L, level, &ar); ++level) {
    if (!lua_getinfo(L, "Sl", &ar)) continue;
    if (ar.currentline <= 0 || !ar.source || ar.source[0] != '@') continue;  // C or unknown
    const std::string file = ar.source + 1;
    if (innermost.file.empty()) innermost = ErrorLocation{file, ar.currentline, ""};
    if (!is_library(file)) return ErrorLocation{file, ar.currentline, ""};
  }
  return innermost;
}

std::optional<std::string> LuaHost::file_for_chunk_id(std::string_view src) const {
  // Lua shortens long chunk names to "...<tail>" in messages.
  const bool truncated = src.substr(0, 3) == "...";
  if (truncated) src.remove_prefix(3);
  for (const auto& f : files_) {
    if (f == src) return f;
    if (truncated && f.size() >= src.size() &&
        f.compare(f.size() - src.size(), src.size(), src) == 0)
      return f;
  }
  return std::nullopt;
}

void LuaHost::on_count(lua_State* L, lua_Debug*) {
  lua_getfield(L, LUA_REGISTRYINDEX, kHostKey);
  auto* host = static_cast<LuaHost*>(lua_touserdata(L, -1));
  lua_pop(L, 1);
  if (!host) return;
  host->instructions_ += kCountStep;
  if (host->instructions_ > host->instruction_limit_) host->fail_too_long(L);
  host->check_deadline(L);
}

void LuaHost::fail_too_long(lua_State* L) {
  // Once over, check at every instruction and fail every time, so that a
  // script that catches the error with pcall and loops on is stopped at its
  // first instruction outside the pcall.
  instructions_ = instruction_limit_ + 1;
  lua_sethook(L, &LuaHost::on_count, LUA_MASKCOUNT, 1);
  if (seconds_limit_ > 0 && std::chrono::steady_clock::now() > deadline_)
    luaL_error(L, "the script ran too long (more than %g s)", seconds_limit_);
  luaL_error(L,
             "the script ran too long (more than %d million Lua instructions, pattern matching "
             "included)",
             int(instruction_limit_ / 1000000));
  std::abort();  // luaL_error does not return
}

void LuaHost::check_deadline(lua_State* L) {
  if (seconds_limit_ > 0 && depth_ > 0 && std::chrono::steady_clock::now() > deadline_)
    fail_too_long(L);
}

void LuaHost::charge_work(lua_State* L, std::uint64_t steps) {
  work_pending_ += steps;
  if (work_pending_ < kWorkQuantum) return;
  const std::uint64_t n = work_pending_;
  work_pending_ = 0;
  if (account_.charge) {
    account_.charge(L, n);
    return;
  }
  if (instruction_limit_ > 0 && depth_ > 0) {
    instructions_ += n;
    if (instructions_ > instruction_limit_) fail_too_long(L);
  }
  check_deadline(L);
}

int LuaHost::on_error(lua_State* L) {
  auto* host = static_cast<LuaHost*>(lua_touserdata(L, lua_upvalueindex(1)));
  // Only C++ exceptions of our own are caught here; a Lua error raised while
  // describing (out of memory) makes the call fail with LUA_ERRERR instead.
  try {
    host->describe_failure(L);
  } catch (const std::exception&) {
    host->failure_.reset();
  }
  lua_settop(L, 1);
  return 1;
}

void LuaHost::describe_failure(lua_State* L) {
  Failure f;
  std::string message;
  std::optional<ErrorLocation> given;  // an error table that carries its own file and line
  bool structured = false;
  switch (lua_type(L, 1)) {
    case LUA_TTABLE: {
      auto field = [&](const char* key) -> std::optional<std::string> {
        lua_pushstring(L, key);
        lua_rawget(L, 1);  // raw: no metamethod of the script runs here
        std::optional<std::string> out;
        if (lua_type(L, -1) == LUA_TSTRING || lua_type(L, -1) == LUA_TNUMBER) {
          std::size_t n = 0;
          lua_pushvalue(L, -1);
          const char* s = lua_tolstring(L, -1, &n);
          out = std::string(s, n);
          lua_pop(L, 1);
        }
        lua_pop(L, 1);
        return out;
      };
      if (auto m = field("message")) {
        structured = true;
        message = *m;
      } else {
        message = "error object is a table without a 'message'";
      }
      if (auto o = field("object")) f.where.object = *o;
      if (auto file = field("file")) {
        auto line = field("line");
        given = ErrorLocation{*file, line ? std::atoi(line->c_str()) : 0, ""};
      }
      break;
    }
    case LUA_TSTRING:
    case LUA_TNUMBER: {
      std::size_t n = 0;
      lua_pushvalue(L, 1);
      const char* s = lua_tolstring(L, -1, &n);
      message.assign(s, n);
      lua_pop(L, 1);
      break;
    }
    default:
      message = std::string("error object is a ") + luaL_typename(L, 1) + " value";
  }

  // Where did it happen, and whose line is that?
  std::optional<ErrorLocation> inner;
  if (auto loc = split_location(message)) {
    if (auto file = file_for_chunk_id(loc->chunk)) {
      inner = ErrorLocation{*file, loc->line, ""};
      message = loc->message;
    }
  }
  const ErrorLocation user = user_location(L);
  ErrorLocation where;
  if (given) {
    where = *given;
  } else if (inner && !is_library(inner->file)) {
    where = *inner;
  } else if (inner) {
    // Raised inside a library mod: report the user's line, and keep the
    // library's own line in the text for whoever debugs the mod.
    where = user.file.empty() ? *inner : user;
    message += " (in " + inner->file + ":" + std::to_string(inner->line) + ")";
  } else {
    where = user;
  }
  f.where.file = where.file;
  f.where.line = where.line;
  f.message = message;
  if (!structured) {
    luaL_traceback(L, L, nullptr, 1);
    if (const char* tb = lua_tostring(L, -1)) f.traceback = tb;
    lua_pop(L, 1);
  }
  failure_ = std::move(f);
}

void LuaHost::call(int nargs, int nresults, const ErrorLocation& fallback) {
  lua_State* L = L_;
  const int func = lua_gettop(L) - nargs;
  lua_rawgeti(L, LUA_REGISTRYINDEX, handler_ref_);
  lua_insert(L, func);
  failure_.reset();
  if (depth_ == 0 && instruction_limit_ > 0) {
    instructions_ = 0;
    lua_sethook(L, &LuaHost::on_count, LUA_MASKCOUNT, kCountStep);
  }
  if (depth_ == 0) {
    work_pending_ = 0;
    deadline_ = std::chrono::steady_clock::now() +
                std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                    std::chrono::duration<double>(seconds_limit_));
  }
  const std::size_t refusals = budget_->refusals();
  const CStackEntry entry;  // the C stack guard measures from here
  ++depth_;
  const int rc = lua_pcall(L, nargs, nresults, func);
  --depth_;
  lua_remove(L, func);
  if (rc == 0 && budget_->refusals() == refusals) return;
  if (rc == 0) {
    // The script ran out of memory and caught the error in its own pcall.
    // A mod that does so is stopped (mod_runtime); a scene or a manifest is
    // refused the same way, rather than going on at its limit until the
    // instruction budget ends it.
    lua_pop(L, nresults == LUA_MULTRET ? lua_gettop(L) - func + 1 : nresults);
    lua_gc(L, LUA_GCCOLLECT, 0);
    throw InputError(fallback, "out of memory: the script needs more than its budget of " +
                                   std::to_string(memory_limit_ / 1024) +
                                   " KiB (it caught the error in a pcall and went on)");
  }
  // LuaJIT has no emergency collection: after a failure (above all an
  // out-of-memory one) free the failed script's garbage now, so that the
  // host can go on within its budget.
  lua_gc(L, LUA_GCCOLLECT, 0);

  std::string raw = lua_type(L, -1) == LUA_TSTRING ? lua_tostring(L, -1) : "";
  lua_pop(L, 1);
  std::optional<Failure> f = std::move(failure_);
  failure_.reset();
  if (rc == LUA_ERRMEM || (rc == LUA_ERRERR && budget_->refusals() != refusals)) {
    ErrorLocation where = f ? f->where : fallback;
    if (where.file.empty()) where = fallback;
    throw InputError(where, "out of memory: the script needs more than its budget of " +
                                std::to_string(memory_limit_ / 1024) + " KiB");
  }
  if (rc == LUA_ERRERR || !f)
    throw InputError(fallback, raw.empty() ? "error while handling an error" : raw);
  if (f->where.file.empty()) {
    f->where.file = fallback.file;
    f->where.line = fallback.line;
  }
  std::string message = f->message;
  if (!f->traceback.empty()) message += "\n" + f->traceback;
  throw InputError(f->where, message);
}

}  // namespace alloy::lua
