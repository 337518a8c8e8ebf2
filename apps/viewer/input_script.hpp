// Scripted input: a text file of mouse and key events, each at a frame, that
// the viewer turns into SDL events (SDL_PushEvent) before that frame, so that
// headless runs and tests drive the viewer exactly as a player's hand does.
//
//   # frame  event      arguments            (positions in play-area metres)
//   10       press      0.3 1.5              left button down at x = 0.3 m, y = 1.5 m
//   12       move       0.8 1.6
//   14       release    0.8 1.6
//   20       rpress     0.5 1.0              right button (r-) variants
//   30       key        space                a key by its SDL name: space, p, r, w, Delete, ...
//   40       wheel      1                    mouse wheel notches (turns a carried part)
//   50       key        ctrl+z               with modifiers: ctrl+, shift+ (ctrl+shift+s)
//   52       keydown    shift                holds a modifier (shift, ctrl or alt) down from this
//                                            frame until its keyup: a press, drag or key between
//                                            them has it (shift+click, a shift-drag's rubber band)
//   58       keyup      shift
//   60       text       lever.lua            types text into the field that has the focus
//   70       palette    steel bar            picks a palette entry by its label (as a click on
//                                            its button): the next press puts it there
//   80       set        spring_stiffness 40  the selected object's property as the inspector
//                                            sets it (typed in its field, Enter): numbers,
//                                            vectors as x y z, angles (orientation) in degrees,
//                                            true/false, a list's entry by name; `set material
//                                            felt` picks from the material list
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "apps/viewer/part_geometry.hpp"

namespace alloy::viewer {

struct ScriptEvent {
  enum class Kind {
    Press,
    Move,
    Release,
    RightPress,
    RightRelease,
    Key,
    Wheel,
    Text,
    Palette,
    Set,
    ModifierDown,
    ModifierUp
  };
  int frame = 0;
  Kind kind = Kind::Move;
  Vec2 at;                           ///< mouse events, m
  std::string key;                   ///< Key: SDL key name; Text: the text typed; Set: property;
                                     ///< ModifierDown / ModifierUp: shift, ctrl or alt
  std::string value;                 ///< Set: the value as typed
  bool ctrl = false, shift = false;  ///< Key: held with it
  int wheel = 0;                     ///< Wheel: notches
  int line = 0;                      ///< line in the file, for messages
};

/// Parses a script; throws InputError with the file and line of a bad line.
std::vector<ScriptEvent> parse_script(const std::string& text, const std::string& file);
std::vector<ScriptEvent> read_script(const std::filesystem::path& path);

}  // namespace alloy::viewer
