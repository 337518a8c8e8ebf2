// `alloy plugins` against a hostile mod (the adversary's F9): control
// characters in a mod's doc reach the terminal only escaped in text output,
// and names and interaction functions have limits, refused at registration
// with the mod's file and line (docs/security.md).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/alloy/commands.hpp"
#include "tests/apps/cli_runner.hpp"

namespace alloy::app {
namespace {

using cli_test::cli;
using cli_test::Result;

/// A runtime-only mod folder `name` under a fresh temp directory, removed after.
class ModFolder {
 public:
  ModFolder(const std::string& name, const std::string& runtime) {
    static std::atomic<int> counter{0};
    root_ = std::filesystem::temp_directory_path() /
            ("alloy_plugins_text_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::create_directories(root_ / name);
    std::ofstream(root_ / name / "mod.lua")
        << "return { name = \"" << name << "\", version = \"1.0\", runtime = \"runtime.lua\" }\n";
    std::ofstream(root_ / name / "runtime.lua") << runtime;
    path_ = (root_ / name).string();
  }
  ~ModFolder() {
    std::error_code ec;
    std::filesystem::remove_all(root_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::filesystem::path root_;
  std::string path_;
};

bool has_control_character(const std::string& s) {
  for (const char c : s)
    if ((static_cast<unsigned char>(c) < 0x20 && c != '\n') || c == 0x7f) return true;
  return s.find("\xc2\x9b") != std::string::npos;
}

TEST(AlloyPluginsText, AModsControlCharactersArePrintedEscaped) {
  // A newline (a forged line of the listing), ESC [2J (clear the screen),
  // BEL, and U+009B (CSI in one character) in the plugin's, a property's and
  // a function's doc.
  ModFolder mod("ansidoc",
                "mod.property { name = \"ansi_p\", doc = \"bell\\7 here\" }\n"
                "mod.resolver { name = \"ansidoc.r\", doc = \"line1\\nline2\\27[2J\\194\\155x\",\n"
                "  writes = { \"ansi_p\" }, functions = { poke = { \"number\" } },\n"
                "  advance = function(w, dt) end }\n");
  const Result r = cli({"plugins", mod.path()});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_FALSE(has_control_character(r.out));
  EXPECT_NE(
      r.out.find("ansidoc.r (resolver, mod 'ansidoc'): line1\\nline2\\x1b[2J\\xc2\\x9bx (Lua, "
                 "mod 'ansidoc')\n"),
      std::string::npos)
      << r.out;
  // JSON keeps the text as it is (JSON escapes it).
  const Result j = cli({"plugins", mod.path(), "--json"});
  ASSERT_EQ(j.code, kExitOk) << j.err;
  EXPECT_FALSE(has_control_character(j.out));
  bool found = false;
  for (const auto& p : nlohmann::json::parse(j.out)) {
    if (p["name"] != "ansidoc.r") continue;
    found = true;
    EXPECT_EQ(p["doc"], "line1\nline2\x1b[2J\xc2\x9bx (Lua, mod 'ansidoc')");
  }
  EXPECT_TRUE(found);
}

TEST(AlloyPluginsText, NamesLongerThan64AreRefusedWithFileAndLine) {
  const std::string long_name(100000, 'a');
  ModFolder plugin(
      "longname", "mod.resolver { name = \"" + long_name + "\", advance = function(w, dt) end }\n");
  Result r = cli({"plugins", plugin.path()});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("runtime.lua:1: mod.resolver: the name 'aaaaaaaaaaaaaaaaaaaaaaaa...' is "
                       "100000 characters long; names are at most 64"),
            std::string::npos)
      << r.err.substr(0, 400);
  EXPECT_LT(r.err.size(), 1000u);  // the name is not echoed whole

  ModFolder property("longprop", "mod.property { name = \"" + std::string(65, 'p') + "\" }\n");
  r = cli({"plugins", property.path()});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("mod.property: the name 'pppp"), std::string::npos) << r.err;

  ModFolder function("longfn", "mod.resolver { name = \"longfn.r\", functions = { " +
                                   std::string(65, 'f') +
                                   " = { \"number\" } }, advance = function(w, dt) end }\n");
  r = cli({"plugins", function.path()});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("65 characters long; names are at most 64"), std::string::npos) << r.err;

  // 64 is allowed.
  ModFolder ok("okname", "mod.property { name = \"" + std::string(64, 'q') + "\" }\n");
  r = cli({"plugins", ok.path()});
  EXPECT_EQ(r.code, kExitOk) << r.err;
}

TEST(AlloyPluginsText, AResolverDeclaresAtMost64Functions) {
  auto functions = [](int n) {
    std::string s;
    for (int i = 0; i < n; ++i) s += "f" + std::to_string(i) + " = { \"number\" }, ";
    return s;
  };
  ModFolder many("hugefn", "mod.resolver { name = \"hugefn.r\", functions = { " + functions(65) +
                               "}, advance = function(w, dt) end }\n");
  Result r = cli({"plugins", many.path()});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("runtime.lua:1: mod.resolver 'hugefn.r' declares 65 interaction "
                       "functions; a resolver may declare at most 64"),
            std::string::npos)
      << r.err;
  ModFolder enough("somefn", "mod.resolver { name = \"somefn.r\", functions = { " + functions(64) +
                                 "}, advance = function(w, dt) end }\n");
  r = cli({"plugins", enough.path()});
  EXPECT_EQ(r.code, kExitOk) << r.err;
}

}  // namespace
}  // namespace alloy::app
