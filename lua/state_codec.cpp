#include "lua/state_codec.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <lua.hpp>
#include <string_view>
#include <unordered_set>

#include "lua/lua_bridge.hpp"
#include "runtime/error.hpp"

namespace alloy::lua {

namespace {

constexpr int kCdata = 10;  // LuaJIT's type tag of FFI values (not in lua.h)
constexpr std::size_t kKeyShown = 40;

/// A key as it reads in a path: .name, ["any text"], [3].
std::string key_text(int type, double number, std::string_view text) {
  if (type == LUA_TNUMBER) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "[%.17g]", number);
    return buf;
  }
  bool ident = !text.empty() && !std::isdigit(static_cast<unsigned char>(text[0]));
  for (char c : text) ident = ident && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (ident && text.size() <= kKeyShown) return "." + std::string(text);
  std::string s = "[\"";
  for (std::size_t i = 0; i < text.size() && i < kKeyShown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '"' || c == '\\') {
      s += '\\';
      s += char(c);
    } else if (c < 0x20 || c >= 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      s += buf;
    } else {
      s += char(c);
    }
  }
  if (text.size() > kKeyShown) s += "...(" + std::to_string(text.size()) + " bytes)";
  return s + "\"]";
}

std::string limits_hint() {
  return " (ModBudget::state_bytes, state_entries, state_depth; docs/modding.md, \"Mod state "
         "and migrations\")";
}

struct Key {
  int type;  // LUA_TNUMBER or LUA_TSTRING
  double number;
  std::string_view text;  // points into the Lua string, anchored by the table
};

bool key_less(const Key& a, const Key& b) {
  if (a.type != b.type) return a.type == LUA_TNUMBER;
  if (a.type == LUA_TNUMBER) return a.number < b.number;
  return a.text < b.text;  // char_traits<char>: bytes compared unsigned
}

class Encoder {
 public:
  Encoder(lua_State* L, const std::string& mod, const StateLimits& lim, int cdata_parts)
      : L_(L), mod_(mod), lim_(lim), cdata_parts_(cdata_parts) {}

  std::vector<std::byte> run(int index) {
    if (lua_type(L_, index) != LUA_TTABLE)
      fail(std::string("is a ") + type_name(index) + ", not a table");
    put_byte(kStateFormat);
    table(index, 1);
    return std::move(out_);
  }

 private:
  // The key path is kept as keys and written out only for an error: a
  // snapshot of a large state formats nothing.
  std::string path_text(std::size_t keys) const {
    std::string path = "state";
    for (std::size_t k = 0; k < keys; ++k)
      path += key_text(path_[k].type, path_[k].number, path_[k].text);
    return path;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError("mod '" + mod_ + "': " + path_text(path_.size()) + " " + what);
  }
  std::string type_name(int index) const {
    const int t = lua_type(L_, index);
    if (t == kCdata) return "cdata value (a vec3, a quat or an FFI object)";
    if (t == LUA_TTHREAD) return "coroutine";
    return lua_typename(L_, t);
  }
  void need(std::size_t n) {
    if (n > lim_.bytes || out_.size() > lim_.bytes - n)
      fail("would make the state larger than its limit of " + std::to_string(lim_.bytes) +
           " bytes" + limits_hint());
  }
  void put_byte(std::uint8_t b) {
    need(1);
    out_.push_back(std::byte(b));
  }
  template <class T>
  void put(const T& v) {
    need(sizeof v);
    const auto* p = reinterpret_cast<const std::byte*>(&v);
    out_.insert(out_.end(), p, p + sizeof v);
  }
  void put_text(std::string_view s) {
    need(1 + 8 + s.size());  // before anything is copied: a 100 MB string fails here
    put_byte('s');
    put<std::uint64_t>(s.size());
    const auto* p = reinterpret_cast<const std::byte*>(s.data());
    out_.insert(out_.end(), p, p + s.size());
  }

  void value(int index, std::size_t depth) {
    switch (lua_type(L_, index)) {
      case LUA_TNUMBER:
        put_byte('n');
        put<double>(lua_tonumber(L_, index));
        return;
      case LUA_TBOOLEAN:
        put_byte(lua_toboolean(L_, index) ? 't' : 'f');
        return;
      case LUA_TSTRING: {
        std::size_t n = 0;
        const char* s = lua_tolstring(L_, index, &n);
        put_text({s, n});
        return;
      }
      case LUA_TTABLE:
        table(index, depth + 1);
        return;
      case kCdata:
        if (cdata(index)) return;
        [[fallthrough]];
      default:
        fail("is a " + type_name(index) +
             ": a mod's state holds numbers, strings, booleans and tables of them");
    }
  }

  // A vec3 or a quat: its doubles. Another cdata: false.
  bool cdata(int index) {
    if (cdata_parts_ == 0) return false;
    index = abs_index(L_, index);
    if (!lua_checkstack(L_, 8)) fail("nests too deeply for the Lua stack");
    lua_pushvalue(L_, cdata_parts_);
    lua_pushvalue(L_, index);
    if (lua_pcall(L_, 1, 5, 0) != 0) {
      lua_pop(L_, 1);
      return false;
    }
    const char* kind = lua_tostring(L_, -5);
    const int n = kind && std::strcmp(kind, "vec3") == 0   ? 3
                  : kind && std::strcmp(kind, "quat") == 0 ? 4
                                                           : 0;
    if (n > 0) {
      put_byte(n == 3 ? 'v' : 'q');
      for (int i = 0; i < n; ++i) put<double>(lua_tonumber(L_, -4 + i));
    }
    lua_pop(L_, 5);
    return n > 0;
  }

  void table(int index, std::size_t depth) {
    index = abs_index(L_, index);
    if (depth > lim_.depth)
      fail("nests tables deeper than the limit of " + std::to_string(lim_.depth) + limits_hint());
    if (lua_getmetatable(L_, index)) {
      lua_pop(L_, 1);
      fail(
          "has a metatable: a state's tables are plain (its __index or __pairs would decide "
          "what is saved, and it would not come back); keep the data, set the metatable again "
          "after a restore");
    }
    const void* self = lua_topointer(L_, index);
    for (std::size_t i = 0; i < on_path_.size(); ++i)
      if (on_path_[i] == self) {
        fail("is " + path_text(i) + " again: a cycle (a state is a tree of tables)");
      }
    if (!seen_.insert(self).second)
      fail(
          "is a table already saved under another key: a state is a tree (one table under two "
          "keys would come back as two tables); keep a key to it instead");
    if (!lua_checkstack(L_, 8)) fail("nests too deeply for the Lua stack");

    std::vector<Key> keys;
    for (lua_pushnil(L_); lua_next(L_, index); lua_pop(L_, 1)) {
      const int t = lua_type(L_, -2);
      if (t == LUA_TNUMBER) {
        keys.push_back({t, lua_tonumber(L_, -2), {}});
      } else if (t == LUA_TSTRING) {
        std::size_t n = 0;
        const char* s = lua_tolstring(L_, -2, &n);
        keys.push_back({t, 0, {s, n}});
      } else {
        const std::string what = type_name(-2);
        lua_pop(L_, 2);
        fail("has a key that is a " + what + "; keys are strings or numbers");
      }
      if (++entries_ > lim_.entries) {
        lua_pop(L_, 2);
        fail("takes the state past its limit of " + std::to_string(lim_.entries) + " entries" +
             limits_hint());
      }
    }
    std::sort(keys.begin(), keys.end(), key_less);
    put_byte('{');
    put<std::uint64_t>(keys.size());
    on_path_.push_back(self);
    for (const Key& k : keys) {
      if (k.type == LUA_TNUMBER) {
        put_byte('n');
        put<double>(k.number);
        lua_pushnumber(L_, k.number);
      } else {
        put_text(k.text);
        lua_pushlstring(L_, k.text.data(), k.text.size());
      }
      path_.push_back(k);
      lua_rawget(L_, index);
      value(-1, depth);
      lua_pop(L_, 1);
      path_.pop_back();
    }
    on_path_.pop_back();
  }

  lua_State* L_;
  const std::string& mod_;
  const StateLimits& lim_;
  int cdata_parts_;
  std::vector<std::byte> out_;
  std::size_t entries_ = 0;
  std::vector<Key> path_;  // on_path_[i] is the table at path_[0 .. i)
  std::vector<const void*> on_path_;
  std::unordered_set<const void*> seen_;
};

/// Reads bytes that check_state may not have seen yet: every read checks.
class Checker {
 public:
  Checker(const std::vector<std::byte>& b, const std::string& mod, const StateLimits& lim)
      : b_(b), mod_(mod), lim_(lim) {}

  void run() {
    if (b_.empty()) fail("it is empty");
    if (b_.size() > lim_.bytes)
      fail("it is " + std::to_string(b_.size()) + " bytes, more than the limit of " +
           std::to_string(lim_.bytes) + limits_hint());
    const auto version = std::uint8_t(byte());
    if (version != kStateFormat)
      fail("it is in format " + std::to_string(version) + "; this build reads format " +
           std::to_string(kStateFormat));
    if (byte() != '{') fail("the state is not a table");
    table(1);
    if (at_ != b_.size())
      fail(std::to_string(b_.size() - at_) + " bytes follow the end of the state");
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError("mod '" + mod_ + "': its saved state is damaged at byte " +
                     std::to_string(at_) + " of " + std::to_string(b_.size()) + ": " + what);
  }
  std::uint8_t byte() {
    if (at_ >= b_.size()) fail("it ends in the middle of a value");
    return std::uint8_t(b_[at_++]);
  }
  template <class T>
  T get() {
    if (b_.size() - at_ < sizeof(T)) fail("it ends in the middle of a value");
    T v;
    std::memcpy(&v, b_.data() + at_, sizeof v);
    at_ += sizeof v;
    return v;
  }
  std::string_view text() {
    const auto n = get<std::uint64_t>();
    if (n > b_.size() - at_) fail("a string of " + std::to_string(n) + " bytes, past the end");
    std::string_view s(reinterpret_cast<const char*>(b_.data() + at_), std::size_t(n));
    at_ += std::size_t(n);
    return s;
  }
  void value(std::size_t depth) {
    switch (byte()) {
      case 'n':
        get<double>();
        return;
      case 's':
        text();
        return;
      case 't':
      case 'f':
        return;
      case 'v':
        for (int i = 0; i < 3; ++i) get<double>();
        return;
      case 'q':
        for (int i = 0; i < 4; ++i) get<double>();
        return;
      case '{':
        table(depth + 1);
        return;
      default:
        --at_;
        fail("an unknown value tag");
    }
  }
  void table(std::size_t depth) {
    if (depth > lim_.depth)
      fail("tables nest deeper than the limit of " + std::to_string(lim_.depth) + limits_hint());
    const auto count = get<std::uint64_t>();
    // Each entry takes at least 10 bytes (a number key and a boolean).
    if (count > (b_.size() - at_) / 10)
      fail("a table of " + std::to_string(count) + " entries, past the end");
    entries_ += std::size_t(count);
    if (entries_ > lim_.entries)
      fail("more entries than the limit of " + std::to_string(lim_.entries) + limits_hint());
    Key last{0, 0, {}};
    for (std::uint64_t i = 0; i < count; ++i) {
      Key k{0, 0, {}};
      const std::size_t key_at = at_;
      switch (byte()) {
        case 'n':
          k = {LUA_TNUMBER, get<double>(), {}};
          if (std::isnan(k.number)) {
            at_ = key_at;
            fail("a key is NaN");
          }
          break;
        case 's':
          k = {LUA_TSTRING, 0, text()};
          break;
        default:
          at_ = key_at;
          fail("a key is neither a number nor a string");
      }
      if (i > 0 && !key_less(last, k)) {
        at_ = key_at;
        fail("keys out of order or repeated");
      }
      last = k;
      value(depth);
    }
  }

  const std::vector<std::byte>& b_;
  const std::string& mod_;
  const StateLimits& lim_;
  std::size_t at_ = 0;
  std::size_t entries_ = 0;
};

// Builds the Lua values of checked bytes. Runs inside lua_pcall: the only
// errors are the allocator's, and nothing here owns memory to release.
struct Builder {
  const std::byte* p;
  template <class T>
  T get() {
    T v;
    std::memcpy(&v, p, sizeof v);
    p += sizeof v;
    return v;
  }
  void text(lua_State* L) {
    const auto n = std::size_t(get<std::uint64_t>());
    lua_pushlstring(L, reinterpret_cast<const char*>(p), n);
    p += n;
  }
  void value(lua_State* L) {
    switch (char(*p++)) {
      case 'n':
        lua_pushnumber(L, get<double>());
        return;
      case 's':
        text(L);
        return;
      case 't':
        lua_pushboolean(L, 1);
        return;
      case 'f':
        lua_pushboolean(L, 0);
        return;
      case 'v':
        cdata(L, 3);
        return;
      case 'q':
        cdata(L, 4);
        return;
      default:
        table(L);
        return;  // '{', checked
    }
  }
  // A vec3 or quat, made by the function at stack index 2 (else a table).
  void cdata(lua_State* L, int n) {
    luaL_checkstack(L, 8, "a mod's state nests too deeply");
    if (lua_isnil(L, 2)) {
      lua_createtable(L, n, 0);
      for (int i = 1; i <= n; ++i) {
        lua_pushnumber(L, get<double>());
        lua_rawseti(L, -2, i);
      }
      return;
    }
    lua_pushvalue(L, 2);
    lua_pushstring(L, n == 3 ? "vec3" : "quat");
    for (int i = 0; i < n; ++i) lua_pushnumber(L, get<double>());
    lua_call(L, n + 1, 1);
  }
  void table(lua_State* L) {
    luaL_checkstack(L, 4, "a mod's state nests too deeply");
    const auto count = get<std::uint64_t>();
    lua_createtable(L, 0, int(std::min<std::uint64_t>(count, 1u << 20)));
    for (std::uint64_t i = 0; i < count; ++i) {
      value(L);  // a key: 'n' or 's'
      value(L);
      lua_rawset(L, -3);
    }
  }
  static int run(lua_State* L) {
    auto* self = static_cast<Builder*>(lua_touserdata(L, 1));
    self->p += 2;  // the format and '{'
    self->table(L);
    return 1;
  }
};

}  // namespace

std::vector<std::byte> encode_state(lua_State* L, int index, const std::string& mod,
                                    const StateLimits& limits, int cdata_parts) {
  StackGuard guard(L);
  if (cdata_parts != 0) cdata_parts = abs_index(L, cdata_parts);
  return Encoder(L, mod, limits, cdata_parts).run(abs_index(L, index));
}

void check_state(const std::vector<std::byte>& bytes, const std::string& mod,
                 const StateLimits& limits) {
  Checker(bytes, mod, limits).run();
}

bool decode_state(lua_State* L, const std::vector<std::byte>& bytes, std::string* error,
                  int cdata_make) {
  if (cdata_make != 0) cdata_make = abs_index(L, cdata_make);
  Builder b{bytes.data()};
  lua_pushcfunction(L, &Builder::run);
  lua_pushlightuserdata(L, &b);
  if (cdata_make != 0)
    lua_pushvalue(L, cdata_make);
  else
    lua_pushnil(L);
  if (lua_pcall(L, 2, 1, 0) != 0) {
    if (error) *error = lua_isstring(L, -1) ? lua_tostring(L, -1) : "an error without a message";
    lua_pop(L, 1);
    return false;
  }
  return true;
}

}  // namespace alloy::lua
