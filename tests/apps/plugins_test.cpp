// Interaction functions as data (runtime/interaction_function.hpp): the
// registry's check that providers of one thing declare the same functions,
// `alloy plugins` (text and JSON, native and mods' plugins), and the
// reference table of docs/modding.md against the registry.
#include "resolvers/plugins.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "apps/alloy/commands.hpp"
#include "resolvers/rigid_body/engine_functions.hpp"
#include "runtime/plugin_registry.hpp"
#include "tests/apps/cli_runner.hpp"

namespace alloy::app {
namespace {

using cli_test::cli;
using cli_test::Result;

const nlohmann::json* plugin(const nlohmann::json& all, const std::string& name) {
  for (const auto& p : all)
    if (p["name"] == name) return &p;
  return nullptr;
}

bool has_name(const nlohmann::json& list, const std::string& name) {
  for (const auto& x : list)
    if ((x.is_string() && x == name) || (x.is_object() && x["name"] == name)) return true;
  return false;
}

// A second rigid-body engine as far as the registry sees it: it provides
// `rigid_body` under another name (the factory is never called).
PluginDef fake_engine(std::vector<InteractionFunction> functions) {
  PluginDef def;
  def.info = {.name = "rigid_body.fake", .kind = StageKind::Resolver, .provides = "rigid_body"};
  def.functions = std::move(functions);
  def.records = rigid::engine_records();
  def.create = [](PluginContext&) -> std::unique_ptr<Stage> { return nullptr; };
  return def;
}

TEST(PluginFunctions, ASecondProviderWithTheSameFunctionsIsAccepted) {
  PluginRegistry registry;
  register_native_plugins(registry);
  EXPECT_NO_THROW(registry.add(fake_engine(rigid::engine_functions())));
  ASSERT_NE(registry.find("rigid_body.fake"), nullptr);
}

TEST(PluginFunctions, ASecondProviderWithOtherFunctionsIsRefusedNamingBoth) {
  PluginRegistry registry;
  register_native_plugins(registry);
  std::vector<InteractionFunction> fns = rigid::engine_functions();
  fns[2].decl.args = {ArgKind::Vec3};  // add_force_at without its point
  try {
    registry.add(fake_engine(fns));
    FAIL() << "a provider with other functions was registered";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'rigid_body.fake'"), std::string::npos) << m;
    EXPECT_NE(m.find("'rigid_body'"), std::string::npos) << m;
    EXPECT_NE(m.find("add_force_at(vec3)"), std::string::npos) << m;
    EXPECT_NE(m.find("add_force_at(vec3, vec3)"), std::string::npos) << m;
  }
  EXPECT_EQ(registry.find("rigid_body.fake"), nullptr);  // nothing registered

  fns = rigid::engine_functions();
  fns.pop_back();  // one function fewer
  EXPECT_THROW(registry.add(fake_engine(fns)), InputError);
  fns = rigid::engine_functions();
  std::swap(fns[0], fns[1]);  // the same functions in another order: bindings number them
  EXPECT_THROW(registry.add(fake_engine(fns)), InputError);
}

TEST(PluginFunctions, TheCheckHoldsWhicheverProviderComesFirst) {
  PluginRegistry registry;
  std::vector<InteractionFunction> fns = rigid::engine_functions();
  fns[0].decl.name = "push";
  registry.add(fake_engine(fns));
  EXPECT_THROW(register_native_plugins(registry), InputError);
}

TEST(PluginFunctions, OnlyResolversDeclareFunctions) {
  PluginRegistry registry;
  PluginDef def = fake_engine(rigid::engine_functions());
  def.info.kind = StageKind::Derived;
  def.info.provides = "";
  EXPECT_THROW(registry.add(def), InputError);
}

TEST(AlloyPlugins, JsonListsOwnershipAndFunctions) {
  Result r = cli({"plugins", "--json"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  const nlohmann::json all = nlohmann::json::parse(r.out);
  ASSERT_TRUE(all.is_array());
  const nlohmann::json* rigid = plugin(all, "rigid_body");
  ASSERT_NE(rigid, nullptr);
  EXPECT_EQ((*rigid)["kind"], "resolver");
  EXPECT_EQ((*rigid)["origin"], "native");
  EXPECT_TRUE(has_name((*rigid)["owns"], "mass"));
  EXPECT_TRUE(has_name((*rigid)["writes"], "position"));
  EXPECT_TRUE(has_name((*rigid)["needs"], "density"));
  const nlohmann::json* add_force = nullptr;
  for (const auto& f : (*rigid)["functions"])
    if (f["name"] == "add_force") add_force = &f;
  ASSERT_NE(add_force, nullptr);
  EXPECT_EQ((*add_force)["args"], nlohmann::json::array({"vec3"}));
  // Electricity owns the current a mod reads; gravity's providers say what they provide.
  bool current_owned = false;
  for (const auto& p : all) current_owned = current_owned || has_name(p["owns"], "current");
  EXPECT_TRUE(current_owned);
  ASSERT_NE(plugin(all, "gravity.nbody"), nullptr);
  EXPECT_EQ((*plugin(all, "gravity.nbody"))["provides"], "gravity");
  ASSERT_NE(plugin(all, "collisions"), nullptr);
  EXPECT_EQ((*plugin(all, "collisions"))["contacts"], true);
  const nlohmann::json* from_gravity = plugin(all, "rigid_body_from_gravity");
  ASSERT_NE(from_gravity, nullptr);
  EXPECT_EQ((*from_gravity)["target"], "rigid_body");
}

TEST(AlloyPlugins, AModsPluginsAreListedWithTheirFunctions) {
  Result r = cli({"plugins", "mods/magic", "--json"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  const nlohmann::json all = nlohmann::json::parse(r.out);
  const nlohmann::json* mana = plugin(all, "magic.mana");
  ASSERT_NE(mana, nullptr) << r.out;
  EXPECT_EQ((*mana)["origin"], "mod");
  EXPECT_EQ((*mana)["mod"], "magic");
  ASSERT_EQ((*mana)["functions"].size(), 1u);
  EXPECT_EQ((*mana)["functions"][0]["name"], "link");
  EXPECT_EQ((*mana)["functions"][0]["args"], nlohmann::json::array({"object"}));
  EXPECT_TRUE(has_name((*mana)["owns"], "mana"));
  // A property none of the mod's stages writes (the rune carved in a stone,
  // an input) is listed too, once, with its kind and values: before, it
  // appeared only as a name in reads and needs.
  int runes = 0;
  for (const auto& p : all)
    for (const auto& o : p["owns"])
      if (o["name"] == "rune") {
        ++runes;
        EXPECT_EQ(o["kind"], "enum");
        EXPECT_EQ(o["values"], nlohmann::json::array({"source", "conduit", "lift"}));
      }
  EXPECT_EQ(runes, 1);
  EXPECT_NE(plugin(all, "rigid_body"), nullptr);  // the natives are there too
}

TEST(AlloyPlugins, TextNamesFunctionsAndOwnership) {
  Result r = cli({"plugins"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("function add_force(vec3)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("function add_force_at(vec3, vec3)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  owns: "), std::string::npos) << r.out;
  Result bad = cli({"plugins", "mods/no_such_mod_here"});
  EXPECT_EQ(bad.code, kExitBadInput);
  EXPECT_NE(bad.err.find("no_such_mod_here"), std::string::npos) << bad.err;
}

// docs/modding.md's reference lists the native properties a mod can read,
// between two markers; regenerate the block with `alloy plugins --doc-table`.
TEST(AlloyPlugins, ModdingDocListsTheRegistrysNativeProperties) {
  std::ifstream in(std::string(ALLOY_SOURCE_DIR) + "/docs/modding.md");
  const std::string doc{std::istreambuf_iterator<char>(in), {}};
  const std::string begin = "<!-- native-properties:begin -->\n";
  const std::string end = "<!-- native-properties:end -->";
  const auto b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos) << "docs/modding.md has no native-properties block";
  ASSERT_NE(e, std::string::npos);
  const std::string block = doc.substr(b + begin.size(), e - b - begin.size());
  Result r = cli({"plugins", "--doc-table"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_EQ(block, r.out) << "docs/modding.md's native property table differs from the "
                             "registry: regenerate it with `build/apps/alloy plugins --doc-table`";
  for (const char* p : {"`current`", "`resistance`", "`mass`"})
    EXPECT_NE(block.find(p), std::string::npos) << p;
}

}  // namespace
}  // namespace alloy::app
