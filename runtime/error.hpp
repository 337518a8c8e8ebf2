// Errors that carry where they came from. Bad input (a scene, a mod, a player's
// edit) must name the file, the line and the object; ErrorLocation is how that
// information travels from the Lua host or the property layer to the CLI.
#pragma once

#include <stdexcept>
#include <string>

namespace alloy {

/// Where a piece of input came from. Any field may be empty / zero.
struct ErrorLocation {
  std::string file;
  int line = 0;
  std::string object;  ///< scene name of the object, if the error concerns one
};

/// Bad input: the CLI maps it to exit code 2. The message is complete on its
/// own; `where` repeats its parts for tools (viewer, tests).
class InputError : public std::runtime_error {
 public:
  InputError(ErrorLocation where, const std::string& message)
      : std::runtime_error(format(where, message)), where_(std::move(where)), bare_(message) {}
  explicit InputError(const std::string& message) : InputError(ErrorLocation{}, message) {}

  const ErrorLocation& where() const { return where_; }
  /// The message without its location prefix.
  const std::string& bare() const { return bare_; }

  static std::string format(const ErrorLocation& w, const std::string& message) {
    std::string s;
    if (!w.file.empty()) {
      s += w.file;
      if (w.line > 0) s += ":" + std::to_string(w.line);
      s += ": ";
    }
    if (!w.object.empty()) s += "object '" + w.object + "': ";
    return s + message;
  }

 private:
  ErrorLocation where_;
  std::string bare_;
};

/// A stage broke a rule of the harness (wrote an undeclared column, used a
/// stale id). A programming error in a plugin, not bad input.
class AccessError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

}  // namespace alloy
