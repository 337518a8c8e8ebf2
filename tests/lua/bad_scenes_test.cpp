// Every malformed scene in tests/lua/bad_scenes/ is refused by `check` with an
// InputError at the file, line and object its first line announces:
//   -- expect: line <N>: [object '<name>': ]<fragment of the message>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>

#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "tests/lua/lua_test_support.hpp"

namespace alloy::lua {
namespace {

namespace fs = std::filesystem;

struct Expectation {
  int line = 0;
  std::string object;
  std::string fragment;
};

Expectation read_expectation(const fs::path& file) {
  std::ifstream in(file);
  std::string first;
  std::getline(in, first);
  static const std::regex kExpect(R"(^-- expect: line (\d+): (object '([^']*)': )?(.*)$)");
  std::smatch m;
  if (!std::regex_match(first, m, kExpect)) return {};
  return {std::stoi(m[1]), m[3], m[4]};
}

std::vector<std::string> bad_scenes() {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(test::source_path("tests/lua/bad_scenes")))
    if (entry.path().extension() == ".lua") out.push_back(entry.path().stem().string());
  std::sort(out.begin(), out.end());
  return out;
}

class BadScene : public ::testing::TestWithParam<std::string> {};

TEST_P(BadScene, IsRefusedWhereItsFirstLineSays) {
  const fs::path file = test::source_path("tests/lua/bad_scenes/" + GetParam() + ".lua");
  const Expectation want = read_expectation(file);
  ASSERT_GT(want.line, 0) << file << ": the first line must be -- expect: line N: ...";

  PluginRegistry registry;
  register_native_plugins(registry);
  try {
    check(file, registry);
    FAIL() << file << " passed the check";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.where().file, file.string()) << what;
    EXPECT_EQ(e.where().line, want.line) << what;
    EXPECT_EQ(e.where().object, want.object) << what;
    EXPECT_NE(e.bare().find(want.fragment), std::string::npos) << what;
    // The printed form the CLI shows: file:line: [object 'x': ]message
    const std::string prefix = file.string() + ":" + std::to_string(want.line) + ": " +
                               (want.object.empty() ? "" : "object '" + want.object + "': ");
    EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(Files, BadScene, ::testing::ValuesIn(bad_scenes()),
                         [](const auto& info) { return info.param; });

TEST(BadScenes, ThereAreAtLeastTen) {
  EXPECT_GE(bad_scenes().size(), 10u);
}

}  // namespace
}  // namespace alloy::lua
