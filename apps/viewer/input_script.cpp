#include "apps/viewer/input_script.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "runtime/error.hpp"

namespace alloy::viewer {

std::vector<ScriptEvent> parse_script(const std::string& text, const std::string& file) {
  static const std::map<std::string, ScriptEvent::Kind> kinds = {
      {"press", ScriptEvent::Kind::Press},           {"move", ScriptEvent::Kind::Move},
      {"release", ScriptEvent::Kind::Release},       {"rpress", ScriptEvent::Kind::RightPress},
      {"rrelease", ScriptEvent::Kind::RightRelease}, {"key", ScriptEvent::Kind::Key},
      {"wheel", ScriptEvent::Kind::Wheel},           {"text", ScriptEvent::Kind::Text},
      {"palette", ScriptEvent::Kind::Palette},       {"set", ScriptEvent::Kind::Set},
      {"keydown", ScriptEvent::Kind::ModifierDown},  {"keyup", ScriptEvent::Kind::ModifierUp}};
  std::vector<ScriptEvent> out;
  std::istringstream in(text);
  int n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    std::string kind;
    ScriptEvent e;
    e.line = n;
    if (!(ls >> e.frame)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw InputError(ErrorLocation{file, n, ""}, "expected a frame number first");
    }
    if (!(ls >> kind) || !kinds.count(kind))
      throw InputError(
          ErrorLocation{file, n, ""},
          "expected an event: press, move, release, rpress, rrelease, key, keydown, keyup, wheel, "
          "text, palette or set");
    e.kind = kinds.at(kind);
    bool ok = true;
    switch (e.kind) {
      case ScriptEvent::Kind::Key:
        ok = bool(ls >> e.key);
        // Modifiers before the key's name: ctrl+z, ctrl+shift+s.
        for (bool more = true; ok && more;) {
          more = false;
          for (const char* m : {"ctrl+", "shift+"})
            if (e.key.size() > std::strlen(m) && e.key.compare(0, std::strlen(m), m) == 0) {
              (m[0] == 'c' ? e.ctrl : e.shift) = true;
              e.key.erase(0, std::strlen(m));
              more = true;
            }
        }
        break;
      case ScriptEvent::Kind::Text:
        ok = bool(ls >> e.key);
        break;
      case ScriptEvent::Kind::Palette:
        std::getline(ls >> std::ws, e.key);
        while (!e.key.empty() && (e.key.back() == ' ' || e.key.back() == '\r')) e.key.pop_back();
        ok = !e.key.empty();
        break;
      case ScriptEvent::Kind::Set:
        ok = bool(ls >> e.key);
        std::getline(ls >> std::ws, e.value);
        while (!e.value.empty() && (e.value.back() == ' ' || e.value.back() == '\r'))
          e.value.pop_back();
        ok = ok && !e.value.empty();
        break;
      case ScriptEvent::Kind::Wheel:
        ok = bool(ls >> e.wheel);
        break;
      case ScriptEvent::Kind::ModifierDown:
      case ScriptEvent::Kind::ModifierUp:
        // Only modifiers are held: any other key is pressed and let go by `key`.
        ok = bool(ls >> e.key);
        if (ok && e.key != "shift" && e.key != "ctrl" && e.key != "alt")
          throw InputError(ErrorLocation{file, n, ""},
                           "'" + kind + "' holds a modifier: shift, ctrl or alt, not '" + e.key +
                               "' (press other keys with 'key')");
        break;
      default:
        ok = bool(ls >> e.at.x >> e.at.y);
        break;
    }
    if (!ok || e.frame < 0)
      throw InputError(ErrorLocation{file, n, ""}, "bad arguments for '" + kind + "'");
    out.push_back(e);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const ScriptEvent& a, const ScriptEvent& b) { return a.frame < b.frame; });
  return out;
}

std::vector<ScriptEvent> read_script(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(ErrorLocation{path.string(), 0, ""}, "cannot read the input script");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_script(ss.str(), path.string());
}

}  // namespace alloy::viewer
