#include "lua/lua_patterns.hpp"

#include <cstring>
#include <lua.hpp>
#include <string_view>

#include "lua/c_stack.hpp"

namespace alloy::lua {

namespace {

constexpr int kMaxCaptures = 32;  // Lua's LUA_MAXCAPTURES
constexpr int kMaxDepth = 200;    // nested item matches before "pattern too complex", as LuaJIT
constexpr std::ptrdiff_t kOpen = -1;
constexpr std::ptrdiff_t kPosition = -2;
constexpr std::size_t kBytesPerStep = 16;  // bytes compared or copied per step

// Thrown inside the matcher only, caught by the Lua function that called it:
// no Lua frame is ever between the throw and the catch.
struct PatternError {
  const char* message;
};
struct OutOfSteps {};

unsigned char uc(char c) {
  return static_cast<unsigned char>(c);
}

// The character classes, ASCII only (as LuaJIT: no locale).
bool is_alpha(unsigned c) {
  return (c | 0x20) >= 'a' && (c | 0x20) <= 'z';
}
bool is_digit(unsigned c) {
  return c >= '0' && c <= '9';
}
bool is_graph(unsigned c) {
  return c > 32 && c < 127;
}

bool class_match(unsigned c, unsigned cls) {
  const unsigned lower = (cls >= 'A' && cls <= 'Z') ? cls + 32 : cls;
  bool in = false;
  switch (lower) {
    case 'a':
      in = is_alpha(c);
      break;
    case 'c':
      in = c < 32 || c == 127;
      break;
    case 'd':
      in = is_digit(c);
      break;
    case 'g':
      in = is_graph(c);
      break;
    case 'l':
      in = c >= 'a' && c <= 'z';
      break;
    case 'p':
      in = is_graph(c) && !is_alpha(c) && !is_digit(c);
      break;
    case 's':
      in = c == ' ' || (c >= '\t' && c <= '\r');
      break;
    case 'u':
      in = c >= 'A' && c <= 'Z';
      break;
    case 'w':
      in = is_alpha(c) || is_digit(c);
      break;
    case 'x':
      in = is_digit(c) || ((c | 0x20) >= 'a' && (c | 0x20) <= 'f');
      break;
    case 'z':
      in = c == 0;
      break;
    default:
      return cls == c;  // %. %% %( ...: the character itself
  }
  return lower == cls ? in : !in;  // an upper-case class is the complement
}

/// `c` in the set whose '[' is at `p` and whose ']' is at `close`.
bool in_set(unsigned c, const char* p, const char* close) {
  bool yes = true;
  ++p;
  if (*p == '^') {
    yes = false;
    ++p;
  }
  for (; p < close; ++p) {
    if (*p == '%') {
      ++p;
      if (class_match(c, uc(*p))) return yes;
    } else if (p[1] == '-' && p + 2 < close) {
      if (uc(p[0]) <= c && c <= uc(p[2])) return yes;
      p += 2;
    } else if (uc(*p) == c) {
      return yes;
    }
  }
  return !yes;
}

/// Just past the single-character item (a character, '.', %x or a set) at `p`.
const char* item_end(const char* p) {
  const char c = *p++;
  if (c == '%') {
    if (*p == '\0') throw PatternError{"malformed pattern (ends with '%')"};
    return p + 1;
  }
  if (c == '[') {
    if (*p == '^') ++p;
    // The first character of a set is a member even when it is ']'.
    do {
      if (*p == '\0') throw PatternError{"malformed pattern (missing ']')"};
      if (*p++ == '%' && *p != '\0') ++p;
    } while (*p != ']');
    return p + 1;
  }
  return p;
}

bool item_matches(unsigned c, const char* p, const char* end) {
  switch (*p) {
    case '.':
      return true;
    case '%':
      return class_match(c, uc(p[1]));
    case '[':
      return in_set(c, p, end - 1);
    default:
      return uc(*p) == c;
  }
}

/// One subject, one pattern (NUL-terminated, as Lua's strings are: a
/// pattern ends at its first NUL, as in LuaJIT), a running count of steps.
class Matcher {
 public:
  Matcher(const char* subject, std::size_t size, std::uint64_t limit)
      : begin_(subject), end_(subject + size), limit_(limit) {}

  /// The end of a match of `p` starting at `s`, or null. Captures are reset.
  const char* match_at(const char* s, const char* p) {
    level_ = 0;
    depth_ = 0;
    return match(s, p);
  }

  void charge(std::uint64_t n) {
    steps_ += n;
    if (steps_ > limit_) throw OutOfSteps{};
  }
  std::uint64_t steps() const { return steps_; }
  const char* begin() const { return begin_; }
  const char* end() const { return end_; }

  int level() const { return level_; }
  /// Pushes capture `i` (the whole match s..e when there are no captures).
  void push_capture(lua_State* L, int i, const char* s, const char* e) const;
  /// Pushes all captures (or the whole match if none and `s` is given).
  int push_captures(lua_State* L, const char* s, const char* e) const;
  /// Checks a capture before it is pushed (errors must be raised outside).
  const char* capture_problem(int i, bool whole_allowed) const;

 private:
  void step() {
    if (++steps_ > limit_) throw OutOfSteps{};
  }

  const char* match(const char* s, const char* p);
  const char* repeat_max(const char* s, const char* p, const char* ep);
  const char* repeat_min(const char* s, const char* p, const char* ep);
  const char* open_capture(const char* s, const char* p, std::ptrdiff_t what);
  const char* close_capture(const char* s, const char* p);
  const char* balanced(const char* s, const char* p);
  const char* back_reference(const char* s, char digit);

  const char* begin_;
  const char* end_;
  std::uint64_t limit_;
  std::uint64_t steps_ = 0;
  int level_ = 0;  // captures opened (finished or not)
  int depth_ = 0;  // nested match() calls
  struct {
    const char* start;
    std::ptrdiff_t len;  // kOpen while unfinished, kPosition for ()
  } cap_[kMaxCaptures];
};

const char* Matcher::match(const char* s, const char* p) {
  if (++depth_ > kMaxDepth) throw PatternError{"pattern too complex"};
  struct Leave {
    int& depth;
    ~Leave() { --depth; }
  } leave{depth_};
  for (;;) {
    step();
    switch (*p) {
      case '\0':
        return s;
      case '(':
        return p[1] == ')' ? open_capture(s, p + 2, kPosition) : open_capture(s, p + 1, kOpen);
      case ')':
        return close_capture(s, p + 1);
      case '$':
        if (p[1] == '\0') return s == end_ ? s : nullptr;
        break;  // a '$' elsewhere is the character
      case '%':
        if (p[1] == 'b') {
          s = balanced(s, p + 2);
          if (!s) return nullptr;
          p += 4;
          continue;
        }
        if (p[1] == 'f') {
          p += 2;
          if (*p != '[') throw PatternError{"missing '[' after '%f' in pattern"};
          const char* ep = item_end(p);
          const unsigned before = s == begin_ ? 0 : uc(s[-1]);
          const unsigned here = s < end_ ? uc(*s) : 0;
          if (in_set(before, p, ep - 1) || !in_set(here, p, ep - 1)) return nullptr;
          p = ep;
          continue;
        }
        if (is_digit(uc(p[1]))) {
          s = back_reference(s, p[1]);
          if (!s) return nullptr;
          p += 2;
          continue;
        }
        break;  // a class
      default:
        break;
    }
    // A single-character item, perhaps with a quantifier.
    const char* ep = item_end(p);
    const bool hit = s < end_ && item_matches(uc(*s), p, ep);
    switch (*ep) {
      case '?':
        if (hit)
          if (const char* r = match(s + 1, ep + 1)) return r;
        p = ep + 1;
        continue;
      case '*':
        return repeat_max(s, p, ep);
      case '+':
        return hit ? repeat_max(s + 1, p, ep) : nullptr;
      case '-':
        return repeat_min(s, p, ep);
      default:
        if (!hit) return nullptr;
        ++s;
        p = ep;
        continue;
    }
  }
}

const char* Matcher::repeat_max(const char* s, const char* p, const char* ep) {
  std::size_t n = 0;
  while (s + n < end_ && item_matches(uc(s[n]), p, ep)) {
    step();
    ++n;
  }
  for (;;) {  // the longest run first, then one shorter at a time
    if (const char* r = match(s + n, ep + 1)) return r;
    if (n == 0) return nullptr;
    --n;
  }
}

const char* Matcher::repeat_min(const char* s, const char* p, const char* ep) {
  for (;;) {  // the shortest run first, then one longer at a time
    if (const char* r = match(s, ep + 1)) return r;
    if (s < end_ && item_matches(uc(*s), p, ep))
      ++s;
    else
      return nullptr;
  }
}

const char* Matcher::open_capture(const char* s, const char* p, std::ptrdiff_t what) {
  if (level_ >= kMaxCaptures) throw PatternError{"too many captures"};
  cap_[level_].start = s;
  cap_[level_].len = what;
  ++level_;
  const char* r = match(s, p);
  if (!r) --level_;
  return r;
}

const char* Matcher::close_capture(const char* s, const char* p) {
  int i = level_ - 1;
  while (i >= 0 && cap_[i].len != kOpen) --i;
  if (i < 0) throw PatternError{"invalid pattern capture"};
  cap_[i].len = s - cap_[i].start;
  const char* r = match(s, p);
  if (!r) cap_[i].len = kOpen;
  return r;
}

const char* Matcher::balanced(const char* s, const char* p) {
  if (p[0] == '\0' || p[1] == '\0') throw PatternError{"unbalanced pattern"};
  if (s >= end_ || *s != p[0]) return nullptr;
  int open = 1;
  while (++s < end_) {
    step();
    if (*s == p[1]) {  // the closer first: %bxx pairs x with the next x
      if (--open == 0) return s + 1;
    } else if (*s == p[0]) {
      ++open;
    }
  }
  return nullptr;
}

const char* Matcher::back_reference(const char* s, char digit) {
  const int i = digit - '1';
  if (i < 0 || i >= level_ || cap_[i].len == kOpen) throw PatternError{"invalid capture index"};
  if (cap_[i].len == kPosition) return nullptr;  // a position has no text to repeat
  const auto len = std::size_t(cap_[i].len);
  charge(len / kBytesPerStep);
  if (std::size_t(end_ - s) >= len && std::memcmp(cap_[i].start, s, len) == 0) return s + len;
  return nullptr;
}

const char* Matcher::capture_problem(int i, bool whole_allowed) const {
  if (i >= level_) return (i == 0 && whole_allowed) ? nullptr : "invalid capture index";
  if (cap_[i].len == kOpen) return "unfinished capture";
  return nullptr;
}

void Matcher::push_capture(lua_State* L, int i, const char* s, const char* e) const {
  if (i >= level_) {
    lua_pushlstring(L, s, std::size_t(e - s));
  } else if (cap_[i].len == kPosition) {
    lua_pushinteger(L, lua_Integer(cap_[i].start - begin_ + 1));
  } else {
    lua_pushlstring(L, cap_[i].start, std::size_t(cap_[i].len));
  }
}

int Matcher::push_captures(lua_State* L, const char* s, const char* e) const {
  const int n = (level_ == 0 && s) ? 1 : level_;
  for (int i = 0; i < n; ++i) push_capture(L, i, s, e);
  return n;
}

// --- the Lua functions -----------------------------------------------------------

constexpr std::string_view kSpecials = "^$*+?.([%-";

bool has_specials(const char* p, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (p[i] != '\0' && kSpecials.find(p[i]) != std::string_view::npos) return true;
  return false;
}

PatternBudget* budget_of(lua_State* L) {
  return static_cast<PatternBudget*>(lua_touserdata(L, lua_upvalueindex(1)));
}

std::uint64_t allowance(PatternBudget* b) {
  return b ? b->steps_per_call : PatternBudget{}.steps_per_call;
}

void charge(lua_State* L, PatternBudget* b, std::uint64_t steps) {
  if (b && b->charge) b->charge(b->owner, L, steps);
}

std::string millions(std::uint64_t n) {
  if (n >= 1000000 && n % 1000000 == 0) return std::to_string(n / 1000000) + " million";
  return std::to_string(n);
}

/// The end of a call that ran out of steps: refused, with a message that says why.
[[noreturn]] void refuse(lua_State* L, PatternBudget* b, const char* fname, std::size_t size) {
  const std::uint64_t limit = allowance(b);
  const std::string why = std::string(fname) + ": the pattern took more than " + millions(limit) +
                          " steps on a string of " + std::to_string(size) +
                          " bytes (it backtracks without end?)";
  if (b && b->refuse) b->refuse(b->owner, L, why);  // charges the steps as it sees fit
  charge(L, b, limit);
  luaL_error(L, "%s", why.c_str());
  __builtin_unreachable();
}

/// The start offset of find and match: init as Lua 5.1 reads it (negative
/// counts from the end), clamped into the subject.
std::size_t start_offset(lua_State* L, int arg, std::size_t size) {
  lua_Integer init = luaL_optinteger(L, arg, 1);
  if (init < 0) {
    init += lua_Integer(size);
    if (init < 0) init = 0;
  } else if (init > 0) {
    --init;
  }
  return std::size_t(init) > size ? size : std::size_t(init);
}

int find_or_match(lua_State* L, bool find) {
  PatternBudget* b = budget_of(L);
  std::size_t size = 0, plen = 0;
  const char* s = luaL_checklstring(L, 1, &size);
  const char* p = luaL_checklstring(L, 2, &plen);
  const std::size_t start = start_offset(L, 3, size);
  const char* fname = find ? "string.find" : "string.match";

  if (find && (lua_toboolean(L, 4) || !has_specials(p, plen))) {
    const void* at = memmem(s + start, size - start, p, plen);
    charge(L, b, 1 + (size - start) / kBytesPerStep);
    if (!at) {
      lua_pushnil(L);
      return 1;
    }
    const auto pos = static_cast<const char*>(at) - s;
    lua_pushinteger(L, lua_Integer(pos + 1));
    lua_pushinteger(L, lua_Integer(pos + std::ptrdiff_t(plen)));
    return 2;
  }

  Matcher m(s, size, allowance(b));
  const char* pat = p;
  const bool anchored = *pat == '^';
  if (anchored) ++pat;
  const char* from = s + start;
  const char* to = nullptr;
  const char* problem = nullptr;
  bool out_of_steps = false;
  try {
    for (;;) {
      to = m.match_at(from, pat);
      if (to || anchored || from >= m.end()) break;
      ++from;
    }
  } catch (const PatternError& e) {
    problem = e.message;
  } catch (const OutOfSteps&) {
    out_of_steps = true;
  }
  if (out_of_steps) refuse(L, b, fname, size);
  charge(L, b, m.steps());
  if (problem) return luaL_error(L, "%s", problem);
  if (!to) {
    lua_pushnil(L);
    return 1;
  }
  const int n = find ? m.level() : (m.level() == 0 ? 1 : m.level());
  for (int i = 0; i < n; ++i)
    if (const char* why = m.capture_problem(i, !find)) return luaL_error(L, "%s", why);
  luaL_checkstack(L, n + 2, "too many captures");
  if (find) {
    lua_pushinteger(L, lua_Integer(from - s + 1));
    lua_pushinteger(L, lua_Integer(to - s));
    return 2 + m.push_captures(L, nullptr, nullptr);
  }
  return m.push_captures(L, from, to);
}

int bounded_find(lua_State* L) {
  return find_or_match(L, true);
}

int bounded_match(lua_State* L) {
  return find_or_match(L, false);
}

// gmatch's iterator. Upvalues: the budget, the subject, the pattern, the
// offset where the next search starts. As in LuaJIT, '^' is not an anchor
// here (it would match at most once).
int gmatch_next(lua_State* L) {
  PatternBudget* b = budget_of(L);
  std::size_t size = 0;
  const char* s = lua_tolstring(L, lua_upvalueindex(2), &size);
  const char* p = lua_tostring(L, lua_upvalueindex(3));
  auto offset = std::size_t(lua_tointeger(L, lua_upvalueindex(4)));
  Matcher m(s, size, allowance(b));
  const char* from = s + offset;
  const char* to = nullptr;
  const char* problem = nullptr;
  bool out_of_steps = false;
  try {
    for (; from <= m.end(); ++from) {
      to = m.match_at(from, p);
      if (to) break;
    }
  } catch (const PatternError& e) {
    problem = e.message;
  } catch (const OutOfSteps&) {
    out_of_steps = true;
  }
  if (out_of_steps) refuse(L, b, "string.gmatch", size);
  charge(L, b, m.steps());
  if (problem) return luaL_error(L, "%s", problem);
  if (!to) return 0;
  const int n = m.level() == 0 ? 1 : m.level();
  for (int i = 0; i < n; ++i)
    if (const char* why = m.capture_problem(i, true)) return luaL_error(L, "%s", why);
  // An empty match moves on by one, so that the loop ends.
  lua_pushinteger(L, lua_Integer(to - s) + (to == from ? 1 : 0));
  lua_replace(L, lua_upvalueindex(4));
  luaL_checkstack(L, n, "too many captures");
  return m.push_captures(L, from, to);
}

int bounded_gmatch(lua_State* L) {
  luaL_checkstring(L, 1);
  luaL_checkstring(L, 2);
  lua_settop(L, 2);
  lua_pushvalue(L, lua_upvalueindex(1));
  lua_insert(L, 1);
  lua_pushinteger(L, 0);
  lua_pushcclosure(L, gmatch_next, 4);
  return 1;
}

/// Appends the replacement of gsub for the match s..e (its captures in `m`)
/// to `out`. May call into Lua (a function or a table's __index).
void add_replacement(lua_State* L, Matcher& m, luaL_Buffer* out, const char* s, const char* e) {
  switch (lua_type(L, 3)) {
    case LUA_TFUNCTION: {
      lua_pushvalue(L, 3);
      const int n = m.level() == 0 ? 1 : m.level();
      for (int i = 0; i < n; ++i)
        if (const char* why = m.capture_problem(i, true)) luaL_error(L, "%s", why);
      luaL_checkstack(L, n, "too many captures");
      m.push_captures(L, s, e);
      lua_call(L, n, 1);
      break;
    }
    case LUA_TTABLE: {
      if (const char* why = m.capture_problem(0, true)) luaL_error(L, "%s", why);
      m.push_capture(L, 0, s, e);
      lua_gettable(L, 3);
      break;
    }
    default: {  // a string (or a number): %0-%9 are the match and its captures
      std::size_t len = 0;
      const char* r = lua_tolstring(L, 3, &len);
      for (std::size_t i = 0; i < len; ++i) {
        if (r[i] != '%') {
          luaL_addchar(out, r[i]);
          continue;
        }
        ++i;  // r[len] is the string's NUL: a trailing '%' adds it, as in LuaJIT
        const char c = r[i];
        if (!is_digit(uc(c))) {
          luaL_addchar(out, c);
        } else if (c == '0') {
          luaL_addlstring(out, s, std::size_t(e - s));
        } else {
          if (const char* why = m.capture_problem(c - '1', true)) luaL_error(L, "%s", why);
          m.push_capture(L, c - '1', s, e);
          luaL_addvalue(out);
        }
      }
      m.charge(1 + len / kBytesPerStep);
      return;
    }
  }
  if (!lua_toboolean(L, -1)) {  // nil or false: keep the match as it was
    lua_pop(L, 1);
    lua_pushlstring(L, s, std::size_t(e - s));
  } else if (!lua_isstring(L, -1)) {
    luaL_error(L, "invalid replacement value (a %s)", luaL_typename(L, -1));
  }
  std::size_t added = 0;
  lua_tolstring(L, -1, &added);
  m.charge(1 + added / kBytesPerStep);
  luaL_addvalue(out);
}

int bounded_gsub(lua_State* L) {
  check_c_stack(L);  // a replacement function may call gsub again
  PatternBudget* b = budget_of(L);
  std::size_t size = 0;
  const char* src = luaL_checklstring(L, 1, &size);
  const char* p = luaL_checkstring(L, 2);
  const int type = lua_type(L, 3);
  const lua_Integer max = luaL_optinteger(L, 4, lua_Integer(size) + 1);
  luaL_argcheck(
      L, type == LUA_TNUMBER || type == LUA_TSTRING || type == LUA_TFUNCTION || type == LUA_TTABLE,
      3, "string/function/table expected");
  const bool anchored = *p == '^';
  if (anchored) ++p;

  Matcher m(src, size, allowance(b));
  luaL_Buffer out;
  luaL_buffinit(L, &out);
  const char* s = src;
  lua_Integer n = 0;
  while (n < max) {
    const char* e = nullptr;
    const char* problem = nullptr;
    bool out_of_steps = false;
    try {
      e = m.match_at(s, p);
    } catch (const PatternError& err) {
      problem = err.message;
    } catch (const OutOfSteps&) {
      out_of_steps = true;
    }
    if (out_of_steps) refuse(L, b, "string.gsub", size);
    if (problem) luaL_error(L, "%s", problem);
    if (e) {
      ++n;
      try {
        add_replacement(L, m, &out, s, e);
      } catch (const OutOfSteps&) {
        out_of_steps = true;
      }
      if (out_of_steps) refuse(L, b, "string.gsub", size);
    }
    if (e && e > s) {
      s = e;
    } else if (s < m.end()) {
      luaL_addchar(&out, *s++);
    } else {
      break;
    }
    if (anchored) break;
  }
  luaL_addlstring(&out, s, std::size_t(m.end() - s));
  luaL_pushresult(&out);
  lua_pushinteger(L, n);
  charge(L, b, m.steps() + size / kBytesPerStep);
  return 2;
}

}  // namespace

void install_bounded_patterns(lua_State* L, int index, PatternBudget* budget) {
  if (index < 0 && index > LUA_REGISTRYINDEX) index = lua_gettop(L) + index + 1;
  const luaL_Reg fns[] = {{"find", bounded_find},
                          {"match", bounded_match},
                          {"gmatch", bounded_gmatch},
                          {"gsub", bounded_gsub}};
  for (const auto& f : fns) {
    lua_pushlightuserdata(L, budget);
    lua_pushcclosure(L, f.func, 1);
    lua_setfield(L, index, f.name);
  }
}

}  // namespace alloy::lua
