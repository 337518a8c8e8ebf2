// The Box2D engine's refusals at a scene's load name the file and the line
// of the object, as every other input error does (the adversary's F18: they
// named the scene only).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>

#include "apps/alloy/commands.hpp"
#include "tests/apps/cli_runner.hpp"

namespace alloy::app {
namespace {

using cli_test::cli;
using cli_test::Result;

/// `alloy check` of a Box2D scene whose third line is `line3`.
Result check_box2d_scene(const std::string& line3, const std::string& line4 = "") {
  static std::atomic<int> counter{0};
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("alloy_box2d_lines_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::create_directories(dir);
  const auto file = dir / "scene.lua";
  std::ofstream(file) << "world { dt = 1/240, use = { rigid_body = \"rigid_body.box2d\" } }\n"
                         "object { name = \"floor\", shape = \"box\", size = { 6, 0.1, 1 }, "
                         "position = { 0, -0.05 }, static = true }\n"
                      << line3 << "\n"
                      << line4 << "\n";
  Result r = cli({"check", file.string()});
  std::filesystem::remove_all(dir);
  return r;
}

TEST(Box2DLines, APartOffThePlaneIsNamedWithItsLine) {
  const Result r = check_box2d_scene(
      "object { name = \"x\", shape = \"sphere\", radius = 0.05, mass = 1, position = { 0, 1, "
      "0.3 } }");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("scene.lua:3: object 'x': rigid_body.box2d: 'x' lies off the plane"),
            std::string::npos)
      << r.err;
}

TEST(Box2DLines, AHingeAcrossThePlaneIsNamedWithItsLine) {
  const Result r = check_box2d_scene(
      "object { name = \"p\", shape = \"box\", size = { 0.5, 0.05, 0.05 }, mass = 1, position = { "
      "0, 1 } }",
      "object { name = \"h\", joint = \"hinge\", body_a = \"p\", anchor = { 0.25, 1, 0 }, axis = "
      "{ 1, 0, 0 } }");
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("scene.lua:4: object 'h': rigid_body.box2d: 'h' is a hinge whose axis"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace alloy::app
