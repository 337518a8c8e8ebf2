// What the fuzz targets share: a scratch folder, and the rule of what counts
// as handled.
#pragma once

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "runtime/error.hpp"

namespace alloy::fuzz {

namespace fs = std::filesystem;

/// A folder of this process under the temp directory, removed at exit. Each
/// target works in its own sub-folder, rewritten for every input.
inline const fs::path& scratch() {
  struct Dir {
    fs::path path;
    Dir() {
      path = fs::temp_directory_path() / ("alloy_fuzz_" + std::to_string(::getpid()));
      fs::remove_all(path);
      fs::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static Dir dir;
  return dir.path;
}

/// An empty folder `name` in the scratch space.
inline fs::path fresh_folder(const std::string& name) {
  const fs::path p = scratch() / name;
  std::error_code ec;
  fs::remove_all(p, ec);
  fs::create_directories(p);
  return p;
}

inline void write_file(const fs::path& file, std::string_view text) {
  fs::create_directories(file.parent_path());
  std::ofstream out(file, std::ios::binary);
  out.write(text.data(), std::streamsize(text.size()));
}

/// ALLOY_FUZZ_STRICT=1: an exception other than InputError (bad input that got
/// no located message) counts as a finding too. Off by default: the CLI turns
/// those into exit code 1, which is handled, if not helpful.
inline bool strict() {
  static const bool on = [] {
    const char* v = std::getenv("ALLOY_FUZZ_STRICT");
    return v && *v && *v != '0';
  }();
  return on;
}

/// ALLOY_FUZZ_VERBOSE=1: print every refusal (to see what a finding or a seed does).
inline bool verbose() {
  static const bool on = [] {
    const char* v = std::getenv("ALLOY_FUZZ_VERBOSE");
    return v && *v && *v != '0';
  }();
  return on;
}

/// Runs `body`; bad input refused with an error is the normal outcome.
template <class F>
void guarded(F&& body) {
  try {
    body();
  } catch (const InputError& e) {
    if (verbose()) std::fprintf(stderr, "alloy fuzz: refused: %s\n", e.what());
  } catch (const std::exception& e) {
    if (verbose()) std::fprintf(stderr, "alloy fuzz: failure: %s\n", e.what());
    if (strict()) {
      std::fprintf(stderr, "alloy fuzz: unexpected exception: %s\n", e.what());
      std::abort();
    }
  }
}

}  // namespace alloy::fuzz
