// The fuzz targets' entry points: each takes the fuzzer's bytes and drives one
// way hostile input enters alloy. The same functions serve the libFuzzer
// binaries (fuzz_main.cpp, clang, ALLOY_FUZZ=ON) and the ordinary test suite,
// which replays every saved input through them (replay_test.cpp), so a crash
// once found stays a test in the g++ build.
//
// An entry returns normally for every input that alloy handles: loaded, run,
// or refused with an error. Anything else (a signal, a sanitizer report, a
// leak, a hang) is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace alloy::fuzz {

/// A scene file's text: loaded (with the source tree's mods on the path),
/// started and stepped a few times.
void scene(const std::uint8_t* data, std::size_t size);

/// A mod folder: its files in one text, each after a line "--- NAME.lua"
/// (before the first such line: mod.lua). Checked as `alloy check` does, then
/// run a few steps if its manifest names a scene.
void mod(const std::uint8_t* data, std::size_t size);

/// A runtime file generated from the bytes (mod_api_program), in a mod whose
/// scene holds a few objects carrying its properties; run a few steps, with a
/// hot reload to a second generated program when the bytes ask for one.
void mod_api(const std::uint8_t* data, std::size_t size);

/// The `alloy` command's arguments, one per line, parsed and run in-process
/// (alloy::app::run_cli) in a scratch folder. Inputs that could write outside
/// it, run without end or need a display are skipped (see cli_arguments_allowed).
void cli(const std::uint8_t* data, std::size_t size);

/// A save file's bytes (runtime/save_file.hpp): read back, and if it reads,
/// fitted to and restored into the space scene. The checksum of an input
/// that starts with the save magic is sealed again first, so that the
/// fuzzer reaches the section parsers instead of stopping at the checksum.
void save(const std::uint8_t* data, std::size_t size);

/// The Lua program mod_api runs for these bytes (for reading a finding).
std::string mod_api_program(const std::uint8_t* data, std::size_t size);

/// Whether the CLI target runs these arguments (one per line): no path that
/// leaves the scratch folder, no `view`, no `--watch`, no number that could make
/// a run long.
bool cli_arguments_allowed(std::string_view text);

/// Runs `entry` on the bytes of `text`.
inline void run(void (*entry)(const std::uint8_t*, std::size_t), std::string_view text) {
  entry(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

}  // namespace alloy::fuzz
