// Tests for apps/alloy: the command line as a user meets it. Runs in-process
// through run_cli (fast), and once through the real binary for exit codes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "apps/alloy/commands.hpp"
#include "tests/apps/cli_runner.hpp"

namespace fs = std::filesystem;

namespace alloy::app {
namespace {

using cli_test::cli;
using cli_test::Result;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

fs::path temp_dir() {
  fs::path d = fs::temp_directory_path() / ("alloy_cli_test_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

const char* kDemo = "mods/rigid_demo";

TEST(AlloyCli, RunNarratesAndSucceeds) {
  Result r = cli({"run", kDemo, "--seconds", "2"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("stages:"), std::string::npos);
  EXPECT_NE(r.out.find("rigid_body"), std::string::npos);
  EXPECT_NE(r.out.find("contact began"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ran 480 steps"), std::string::npos) << r.out;
}

TEST(AlloyCli, TraceIsLongFormatWithNamedObjectsAndComponents) {
  const fs::path trace = temp_dir() / "trace.csv";
  Result r = cli({"run", kDemo, "--steps", "10", "--trace", trace.string(), "--trace-props",
                  "position,mass", "--trace-every", "5", "--quiet"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  std::ifstream in(trace);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "step,time,object,property,value");
  std::set<std::string> steps, props;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 5u) << line;
    steps.insert(f[0]);
    props.insert(f[3]);
    EXPECT_NE(f[2].rfind("#", 0), 0u) << "demo objects are named: " << line;
  }
  EXPECT_EQ(steps, (std::set<std::string>{"0", "5", "10"}));
  EXPECT_TRUE(props.count("position.x") && props.count("position.y") && props.count("position.z"));
  EXPECT_TRUE(props.count("mass"));
  EXPECT_FALSE(fs::exists(trace.string() + ".tmp"));
}

TEST(AlloyCli, SameSceneTwiceGivesAnIdenticalTrace) {
  const fs::path dir = temp_dir();
  for (const char* name : {"a.csv", "b.csv"})
    ASSERT_EQ(
        cli({"run", kDemo, "--seconds", "3", "--trace", (dir / name).string(), "--quiet"}).code,
        kExitOk);
  const std::string a = slurp(dir / "a.csv"), b = slurp(dir / "b.csv");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "traces differ";
}

TEST(AlloyCli, EventsAreJsonLinesWithStepTimeType) {
  const fs::path events = temp_dir() / "events.jsonl";
  ASSERT_EQ(cli({"run", kDemo, "--seconds", "2", "--events", events.string(), "--quiet"}).code,
            kExitOk);
  std::ifstream in(events);
  int n = 0;
  for (std::string line; std::getline(in, line); ++n) {
    auto j = nlohmann::json::parse(line);
    EXPECT_TRUE(j.contains("step") && j.contains("time") && j.contains("type")) << line;
  }
  EXPECT_GT(n, 0);
}

TEST(AlloyCli, ProfileListsStagesAndSkippedPlugins) {
  Result r = cli({"run", kDemo, "--steps", "50", "--profile", "--quiet"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("us/step"), std::string::npos);
  EXPECT_NE(r.out.find("rigid_body"), std::string::npos);
  EXPECT_NE(r.out.find("not instantiated"), std::string::npos);
}

TEST(AlloyCli, HashPrintsTheStateHashSoThatTwoRunsCanBeCompared) {
  Result a = cli({"run", kDemo, "--steps", "20", "--quiet", "--hash-every", "10"});
  ASSERT_EQ(a.code, kExitOk) << a.err;
  const std::regex line(R"(state hash at step (\d+): ([0-9a-f]{16})\n)");
  std::vector<std::string> steps, hashes;
  for (std::sregex_iterator it(a.out.begin(), a.out.end(), line), end; it != end; ++it)
    steps.push_back((*it)[1]), hashes.push_back((*it)[2]);
  EXPECT_EQ(steps, (std::vector<std::string>{"10", "20"})) << a.out;  // none repeated at the end
  ASSERT_EQ(hashes.size(), 2u);
  EXPECT_NE(hashes[0], hashes[1]);  // the demo's bodies fall
  // The same run hashes alike; --hash prints the last line only.
  Result b = cli({"run", kDemo, "--steps", "20", "--quiet", "--hash"});
  ASSERT_EQ(b.code, kExitOk) << b.err;
  EXPECT_EQ(b.out, "state hash at step 20: " + hashes[1] + "\n");
  // Another length, another state.
  Result c = cli({"run", kDemo, "--steps", "21", "--quiet", "--hash"});
  EXPECT_EQ(c.out.find(hashes[1]), std::string::npos) << c.out;
  EXPECT_EQ(cli({"run", kDemo, "--steps", "2", "--hash-every", "0"}).code, kExitBadInput);
}

TEST(AlloyCli, DtOverridesTheScene) {
  Result r = cli({"run", kDemo, "--seconds", "1", "--dt", "0.01"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("ran 100 steps of 0.01 s"), std::string::npos) << r.out;
}

TEST(AlloyCli, BadArgumentsAreBadInput) {
  EXPECT_EQ(cli({"run"}).code, kExitBadInput);
  EXPECT_EQ(cli({"run", kDemo, "--steps", "10", "--seconds", "1"}).code, kExitBadInput);
  EXPECT_EQ(cli({"run", kDemo, "--dt", "-1"}).code, kExitBadInput);
  EXPECT_EQ(cli({"frobnicate"}).code, kExitBadInput);
  Result r = cli({"run", "no/such/scene.lua"});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("no/such/scene.lua"), std::string::npos) << r.err;
  r = cli({"run", kDemo, "--steps", "1", "--trace", "/tmp/x.csv", "--trace-props", "positon"});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("did you mean 'position'"), std::string::npos) << r.err;
}

TEST(AlloyCli, CheckAcceptsTheBundledMods) {
  for (const char* mod : {"mods/kit", kDemo}) {
    Result r = cli({"check", mod});
    EXPECT_EQ(r.code, kExitOk) << mod << ": " << r.err;
  }
}

// Every malformed scene of the Lua tests: exit code 2 from check and run,
// with a message naming the file, the line and the object it expects.
TEST(AlloyCli, MalformedScenesGiveExitCodeTwoWithFileLineAndObject) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator("tests/lua/bad_scenes")) {
    if (entry.path().extension() != ".lua") continue;
    ++count;
    std::ifstream in(entry.path());
    std::string first;
    std::getline(in, first);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(first, m, std::regex("expect: (.*)$"))) << entry.path();
    // "line N: rest" is printed as "FILE:N: rest" (see tests/lua/bad_scenes/README.md).
    std::smatch lm;
    const std::string expect_line = m[1];
    ASSERT_TRUE(std::regex_match(expect_line, lm, std::regex("line ([0-9]+): (.*)")))
        << entry.path();
    const std::string expected = entry.path().string() + ":" + lm[1].str() + ": " + lm[2].str();
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"check", entry.path().string()},
          std::vector<std::string>{"run", entry.path().string(), "--quiet"}}) {
      const std::string& cmd = args[0];
      Result r = cli(args);
      EXPECT_EQ(r.code, kExitBadInput) << cmd << " " << entry.path() << "\n" << r.out << r.err;
      EXPECT_NE(r.err.find(expected), std::string::npos)
          << entry.path() << ": expected '" << expected << "' in: " << r.err;
    }
  }
  EXPECT_GE(count, 10);
}

TEST(AlloyCli, TheBinaryReturnsTheDocumentedExitCodes) {
  const std::string bin = ALLOY_BINARY;
  EXPECT_EQ(std::system((bin + " run mods/rigid_demo --steps 10 --quiet > /dev/null").c_str()), 0);
  const int bad = std::system((bin + " check no/such/scene.lua 2> /dev/null").c_str());
  ASSERT_TRUE(WIFEXITED(bad));
  EXPECT_EQ(WEXITSTATUS(bad), kExitBadInput);
}

TEST(AlloyCli, SwapReplacesAResolverWhileRunning) {
  Result r = cli({"run", "tests/lua/scenes/areas.lua", "--seconds", "0.1", "--swap",
                  "moon:gravity.uniform=gravity.uniform@0.05"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("step     13"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("resolver swapped  (gravity.uniform -> gravity.uniform in moon)"),
            std::string::npos)
      << r.out;
  r = cli({"run", "tests/lua/scenes/areas.lua", "--swap", "mars:gravity.uniform=gravity.uniform"});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("no area is called 'mars'"), std::string::npos) << r.err;
  EXPECT_EQ(cli({"run", "tests/lua/scenes/areas.lua", "--swap", "a=b=c@x"}).code, kExitBadInput);
}

TEST(AlloyCli, ReportPrintsAValueAsTheRunGoes) {
  Result r = cli({"run", kDemo, "--seconds", "1", "--report", "ball.position.y@0.5"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("step    120  t=  0.500 s  report: ball position.y = "), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("step    240  t=  1.000 s  report: ball position.y = "), std::string::npos)
      << r.out;
  r = cli({"run", kDemo, "--report", "ball.position"});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("name a component: x, y or z"), std::string::npos) << r.err;
  EXPECT_EQ(cli({"run", kDemo, "--report", "nobody.mass"}).code, kExitBadInput);
  // A scene may ask for reports itself: the motor reports its rotor's speed.
  r = cli({"run", "mods/motor", "--seconds", "2"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("report: axle angular_velocity.z = "), std::string::npos) << r.out;
}

// --- checks that say what they mean; floods bounded (issue 18) -------------------

/// A mod folder in a fresh temp folder: manifest fields, and files by name.
fs::path write_mod(const std::string& name, const std::string& manifest,
                   const std::vector<std::pair<std::string, std::string>>& files) {
  const fs::path dir = temp_dir() / "mods" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "mod.lua") << "return { name = \"" << name << "\", version = \"1.0\", "
                                 << manifest << " }\n";
  for (const auto& [file, text] : files) std::ofstream(dir / file) << text;
  return dir;
}

int exit_code(const std::string& command) {
  const int rc = std::system(command.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(AlloyCli, CheckFailsWhenAStageFailsWhileChecking) {
  const fs::path dir = write_mod(
      "buildfail", "runtime = \"runtime.lua\", scene = \"scene.lua\"",
      {{"runtime.lua",
        "mod.property { name = \"bf_level\" }\n"
        "mod.resolver { name = \"bf.up\", writes = { \"bf_level\" }, needs = { \"bf_level\" },\n"
        "  build = function(w) error(\"cannot build this\") end,\n"
        "  advance = function(w) end }\n"},
       {"scene.lua", "object { name = \"thing\", bf_level = 1 }\n"}});
  Result r = cli({"check", dir.string()});
  EXPECT_EQ(r.code, kExitBadInput) << r.out << r.err;
  EXPECT_EQ(r.out.find(": ok"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("error: stage 'bf.up' of mod 'buildfail' failed"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("buildfail/runtime.lua:3: cannot build this"), std::string::npos) << r.err;
  EXPECT_EQ(exit_code(std::string(ALLOY_BINARY) + " check " + dir.string() + " > /dev/null 2>&1"),
            kExitBadInput);
}

TEST(AlloyCli, CheckPassesAModThatOnlyHasARuntime) {
  const std::string runtime =
      "mod.property { name = \"rt_level\" }\n"
      "mod.resolver { name = \"rt.up\", writes = { \"rt_level\" }, needs = { \"rt_level\" },\n"
      "  advance = function(w) end }\n"
      "mod.on(\"contact_began\", function(e) end)\n";
  fs::path dir = write_mod("rtonly", "runtime = \"runtime.lua\"", {{"runtime.lua", runtime}});
  Result r = cli({"check", dir.string()});
  EXPECT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("ok (mod 'rtonly' has a runtime and no scene: 1 stage, 1 event handler)"),
            std::string::npos)
      << r.out;
  // Its declarations are checked as a scene would load them.
  dir = write_mod("rtbad", "runtime = \"runtime.lua\"",
                  {{"runtime.lua",
                    "mod.resolver { name = \"rt.bad\", writes = { \"masss\" },\n"
                    "  advance = function(w) end }\n"}});
  r = cli({"check", dir.string()});
  EXPECT_EQ(r.code, kExitBadInput);
  EXPECT_NE(r.err.find("rtbad/runtime.lua:1: resolver 'rt.bad': unknown property 'masss' (did you "
                       "mean 'mass'?)"),
            std::string::npos)
      << r.err;
}

TEST(AlloyCli, AnEmptySceneWarnsThatItHoldsNothing) {
  const fs::path scene = temp_dir() / "empty_scene.lua";
  std::ofstream(scene) << "-- a scene that forgot its objects\nworld { seconds = 0.1 }\n";
  for (const char* cmd : {"check", "run"}) {
    Result r = cli({cmd, scene.string()});
    EXPECT_EQ(r.code, kExitOk) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find("warning: " + scene.string() + ": the scene holds no objects"),
              std::string::npos)
        << cmd << ": " << r.err;
  }
  Result r = cli({"check", kDemo});
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
}

TEST(AlloyCli, CheckFailsWhenThePhysicsRefusesAPartAtTheStart) {
  // A mass the property allows (positive) but the rigid body cannot take: the
  // part is frozen when the world starts, and a check must not say "ok".
  const fs::path scene = temp_dir() / "speck_scene.lua";
  std::ofstream(scene) << "world { seconds = 0.1 }\n"
                          "object { name = \"speck\", shape = \"sphere\", radius = 0.1, "
                          "mass = 1e-300, position = {0, 1, 0} }\n"
                          "object { name = \"ball\", shape = \"sphere\", radius = 0.1, "
                          "mass = 1, position = {1, 1, 0} }\n";
  Result r = cli({"check", scene.string()});
  EXPECT_EQ(r.code, kExitBadInput) << r.out << r.err;
  EXPECT_NE(r.err.find("frozen: speck"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find(": ok"), std::string::npos) << r.out;
}

TEST(AlloyCli, NarrationIsInStepOrder) {
  // Contacts (narrated), reports every few steps, and a mod that prints from
  // its stage every 10th step: all in the order of their steps.
  const fs::path dir = write_mod(
      "chatty", "runtime = \"runtime.lua\", scene = \"scene.lua\", depends = { \"kit\" }",
      {{"runtime.lua",
        "mod.property { name = \"chat\" }\n"
        "mod.resolver { name = \"chatty.talk\", writes = { \"chat\" }, needs = { \"chat\" },\n"
        "  advance = function(w) if w.step % 10 == 0 then print('said at step ' .. w.step) end end "
        "}\n"},
       {"scene.lua",
        slurp("mods/rigid_demo/scene.lua") + "\nobject { name = \"talker\", chat = 0 }\n"}});
  Result r = cli({"run", dir.string(), "--seconds", "2", "--report", "ball.position.y@0.0125"});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  std::istringstream in(r.out);
  std::uint64_t last = 0;
  int said = 0, narrated = 0;
  const std::regex step_line("^step +([0-9]+) "), said_line("^\\[chatty\\] said at step ([0-9]+)$");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    std::uint64_t step;
    if (std::regex_search(line, m, step_line)) {
      step = std::stoull(m[1]);
      narrated += line.find("report:") == std::string::npos;
    } else if (std::regex_match(line, m, said_line)) {
      step = std::stoull(m[1]);
      ++said;
    } else {
      continue;
    }
    EXPECT_GE(step, last) << line << "\n" << r.out;
    last = step;
  }
  EXPECT_EQ(said, 48);
  EXPECT_GT(narrated, 0) << r.out;
}

TEST(AlloyCli, AFloodingModIsStoppedAndWhatTheRunWritesIsBounded) {
  const fs::path dir = write_mod(
      "flood", "runtime = \"runtime.lua\", scene = \"scene.lua\"",
      {{"runtime.lua",
        "mod.property { name = \"wet\" }\n"
        "mod.resolver { name = \"flood.spam\", writes = { \"wet\" }, needs = { \"wet\" },\n"
        "  advance = function(w)\n"
        "    for k = 1, 1e7 do pcall(w.emit, w, 'spam', { text = ('x'):rep(200) }) "
        "print(('y'):rep(100)) end\n"
        "  end }\n"},
       {"scene.lua", "world { seconds = 2 }\nobject { name = \"puddle\", wet = 1 }\n"}});
  const fs::path events = temp_dir() / "flood_events.jsonl";
  Result r = cli({"run", dir.string(), "--events", events.string()});
  ASSERT_EQ(r.code, kExitOk) << r.err;
  EXPECT_NE(r.out.find("ran 480 steps"), std::string::npos);
  EXPECT_NE(r.out.find("mod 'flood' stopped: it printed more than 64 KiB in one step (its budget "
                       "print_bytes_per_step)"),
            std::string::npos)
      << r.out.substr(0, 2000);
  EXPECT_NE(r.out.find("flood/runtime.lua:4"), std::string::npos);
  EXPECT_NE(r.out.find("[flood] ... ("), std::string::npos);
  // At most a step's prints (64 KiB) and a step's events (256 KiB) narrated.
  EXPECT_LT(r.out.size(), 400u << 10);
  EXPECT_LT(fs::file_size(events), 1u << 20);
}

TEST(AlloyCli, ASceneThatPrintsInALoopFailsWithBoundedOutput) {
  const fs::path scene = temp_dir() / "printing_scene.lua";
  std::ofstream(scene) << "object { name = \"a\", position = {0, 1, 0} }\n"
                          "for i = 1, 1e8 do print(('p'):rep(1000)) end\n";
  const std::string bin = ALLOY_BINARY;
  const fs::path out = temp_dir() / "printing_scene.out";
  EXPECT_EQ(exit_code(bin + " check " + scene.string() + " > " + out.string() + " 2>&1"),
            kExitBadInput);
  const std::string text = slurp(out);
  EXPECT_LT(text.size(), (4u << 20) + (64u << 10));
  EXPECT_NE(
      text.find("printing_scene.lua:2: the scene printed more than 4 MiB (a print in a loop?)"),
      std::string::npos)
      << text.substr(text.size() > 2000 ? text.size() - 2000 : 0);
}

}  // namespace
}  // namespace alloy::app
