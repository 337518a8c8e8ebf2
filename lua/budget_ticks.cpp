#include "lua/budget_ticks.hpp"

#include <cctype>
#include <vector>

#include "runtime/error.hpp"

namespace alloy::lua {

namespace {

bool ident_start(char c) {
  return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}
bool ident_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}

/// The level of a long bracket opening at s[i] ("[[" -> 0, "[==[" -> 2), or -1.
int long_bracket(std::string_view s, std::size_t i) {
  if (i >= s.size() || s[i] != '[') return -1;
  std::size_t j = i + 1;
  int level = 0;
  while (j < s.size() && s[j] == '=') ++j, ++level;
  return (j < s.size() && s[j] == '[') ? level : -1;
}

/// The index just past the long bracket closing a level-`level` opening whose
/// content starts at `i` (the end of the text if it is never closed).
std::size_t skip_long(std::string_view s, std::size_t i, int level, int& line) {
  for (; i < s.size(); ++i) {
    if (s[i] == '\n') ++line;
    if (s[i] != ']') continue;
    std::size_t j = i + 1;
    int l = 0;
    while (j < s.size() && s[j] == '=') ++j, ++l;
    if (l == level && j < s.size() && s[j] == ']') return j + 1;
  }
  return s.size();
}

}  // namespace

std::string add_budget_ticks(std::string_view s, const std::string& display) {
  const std::string tick = " " + std::string(kTickName) + "();";
  std::vector<std::size_t> at;  // insertion points, ascending

  // Where we are in `function name(params)`: waiting for '(' or for ')'.
  enum class Fn { None, Name, Params } fn = Fn::None;
  int label = 0;  // tokens of "::" name "::" seen so far
  int line = 1;
  std::size_t i = 0;
  while (i < s.size()) {
    const char c = s[i];
    if (c == '\n') {
      ++line, ++i;
      continue;
    }
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
      continue;
    }
    // Comments.
    if (c == '-' && i + 1 < s.size() && s[i + 1] == '-') {
      i += 2;
      if (int level = long_bracket(s, i); level >= 0) {
        i = skip_long(s, i + std::size_t(level) + 2, level, line);
      } else {
        while (i < s.size() && s[i] != '\n') ++i;
      }
      continue;
    }
    // Strings.
    if (c == '"' || c == '\'') {
      ++i;
      while (i < s.size() && s[i] != c && s[i] != '\n') {
        if (s[i] == '\\' && i + 1 < s.size()) {
          if (s[i + 1] == '\n') ++line;
          ++i;
        }
        ++i;
      }
      if (i < s.size() && s[i] == c) ++i;
      label = 0;
      continue;
    }
    if (int level = long_bracket(s, i); level >= 0) {
      i = skip_long(s, i + std::size_t(level) + 2, level, line);
      label = 0;
      continue;
    }
    // Numbers (with exponents, hex, LuaJIT's LL/ULL/i suffixes).
    if (std::isdigit(static_cast<unsigned char>(c)) ||
        (c == '.' && i + 1 < s.size() && std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
      while (i < s.size()) {
        const char d = s[i];
        if ((d == '+' || d == '-') &&
            (s[i - 1] == 'e' || s[i - 1] == 'E' || s[i - 1] == 'p' || s[i - 1] == 'P')) {
          ++i;
        } else if (ident_char(d) || d == '.') {
          ++i;
        } else {
          break;
        }
      }
      label = 0;
      continue;
    }
    // Names and keywords.
    if (ident_start(c)) {
      const std::size_t start = i;
      while (i < s.size() && ident_char(s[i])) ++i;
      const std::string_view word = s.substr(start, i - start);
      if (word == kTickName)
        throw InputError(ErrorLocation{display, line, ""},
                         "the name " + std::string(kTickName) + " is reserved for the host");
      if (word == "do" || word == "repeat") at.push_back(i);
      if (word == "function") fn = Fn::Name;
      label = label == 1 ? 2 : 0;
      continue;
    }
    // Punctuation that matters: "(" and ")" of a parameter list, "::".
    if (c == ':' && i + 1 < s.size() && s[i + 1] == ':') {
      i += 2;
      if (label == 2) {
        at.push_back(i);  // after "::name::": the target of a goto, maybe backwards
        label = 0;
      } else {
        label = 1;
      }
      continue;
    }
    label = 0;
    if (c == '(' && fn == Fn::Name) fn = Fn::Params;
    if (c == ')' && fn == Fn::Params) {
      at.push_back(i + 1);
      fn = Fn::None;
    }
    ++i;
  }

  std::string out = "return function(" + std::string(kTickName) + ") return function(...)";
  out.reserve(out.size() + s.size() + at.size() * tick.size() + 16);
  std::size_t from = 0;
  for (std::size_t pos : at) {
    out.append(s.substr(from, pos - from));
    out += tick;
    from = pos;
  }
  out.append(s.substr(from));
  out += "\nend end";
  return out;
}

}  // namespace alloy::lua
