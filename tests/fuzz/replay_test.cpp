// Replays the fuzzers' seed corpus and every saved crashing input through the
// same entry functions the libFuzzer binaries call, in the ordinary build: an
// input that once crashed alloy is a regression test that needs no clang.
//
// Folders, per target (scene, mod, mod_api, cli, save):
//   tests/fuzz/corpus/<target>/       seeds: what a fuzzing run starts from,
//                                     with the source folders tests/fuzz/seed_dirs names
//   tests/fuzz/regressions/<target>/  inputs that crashed, hung or leaked, now fixed
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_entries.hpp"

namespace {

namespace fs = std::filesystem;

struct Target {
  const char* name;
  void (*entry)(const std::uint8_t*, std::size_t);
};

const Target kTargets[] = {{"scene", alloy::fuzz::scene},
                           {"mod", alloy::fuzz::mod},
                           {"mod_api", alloy::fuzz::mod_api},
                           {"cli", alloy::fuzz::cli},
                           {"save", alloy::fuzz::save}};

const fs::path kSource = ALLOY_SOURCE_DIR;

/// The files under dir, sub-folders included (as libFuzzer reads a corpus).
void add_files(const fs::path& dir, std::vector<fs::path>& files) {
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec))
    if (it->is_regular_file() && it->path().filename().string()[0] != '.')
      files.push_back(it->path());
}

/// The source folders seed_dirs names for the target.
std::vector<fs::path> seed_dirs(const std::string& target) {
  std::ifstream in(kSource / "tests" / "fuzz" / "seed_dirs");
  std::vector<fs::path> dirs;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string t, dir;
    if (line.empty() || line[0] == '#' || !(words >> t >> dir)) continue;
    if (t == target) dirs.push_back(kSource / dir);
  }
  return dirs;
}

std::vector<fs::path> inputs(const std::string& kind, const std::string& target) {
  std::vector<fs::path> files;
  add_files(kSource / "tests" / "fuzz" / kind / target, files);
  if (kind == "corpus")
    for (const fs::path& dir : seed_dirs(target)) add_files(dir, files);
  std::sort(files.begin(), files.end());
  return files;
}

std::string read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void replay(const std::string& kind, const Target& t) {
  for (const fs::path& file : inputs(kind, t.name)) {
    SCOPED_TRACE(file.string());
    alloy::fuzz::run(t.entry, read(file));  // a crash, a sanitizer report or a leak fails the run
  }
}

class FuzzReplay : public ::testing::TestWithParam<Target> {};

TEST_P(FuzzReplay, EverySavedCrashingInputIsHandled) {
  replay("regressions", GetParam());
}

TEST_P(FuzzReplay, EverySeedIsHandled) {
  // The seeds must exist: an empty corpus would make the fuzzer start blind.
  EXPECT_FALSE(inputs("corpus", GetParam().name).empty());
  if (std::string(GetParam().name) == "scene") {  // the bundled scenes among them
    const auto seeds = inputs("corpus", "scene");
    EXPECT_NE(std::find(seeds.begin(), seeds.end(), kSource / "mods" / "doorbell" / "scene.lua"),
              seeds.end());
  }
  replay("corpus", GetParam());
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzReplay, ::testing::ValuesIn(kTargets),
                         [](const ::testing::TestParamInfo<Target>& info) {
                           return std::string(info.param.name);
                         });

// The generator always produces a program (also from no bytes at all), and
// the same program for the same bytes: a finding's program can be printed
// from its input alone.
TEST(FuzzTargets, TheModApiGeneratorIsDeterministic) {
  const std::string bytes = "\x03\x01\x07\x10\xff\x42";
  const auto* p = reinterpret_cast<const std::uint8_t*>(bytes.data());
  EXPECT_EQ(alloy::fuzz::mod_api_program(p, bytes.size()),
            alloy::fuzz::mod_api_program(p, bytes.size()));
  const std::string empty = alloy::fuzz::mod_api_program(nullptr, 0);
  EXPECT_NE(empty.find("mod.resolver"), std::string::npos);
}

// The CLI target never runs what could leave its scratch folder or run long.
TEST(FuzzTargets, TheCliTargetSkipsArgumentsThatReachOutside) {
  using alloy::fuzz::cli_arguments_allowed;
  EXPECT_TRUE(cli_arguments_allowed("run\ntiny.lua\n--steps\n3"));
  EXPECT_TRUE(cli_arguments_allowed("check\ntinymod"));
  EXPECT_FALSE(cli_arguments_allowed("run\ntiny.lua\n--trace\n/tmp/x.csv"));
  EXPECT_FALSE(cli_arguments_allowed("run\n../tiny.lua"));
  EXPECT_FALSE(cli_arguments_allowed("view\ntiny.lua"));
  EXPECT_FALSE(cli_arguments_allowed("run\ntiny.lua\n--watch"));
  EXPECT_FALSE(cli_arguments_allowed("run\ntiny.lua\n--steps\n100000"));
  EXPECT_FALSE(cli_arguments_allowed("run\ntiny.lua\n--steps=0x7fffffff"));
  EXPECT_FALSE(cli_arguments_allowed("run\ntiny.lua\n--dt\n1e-9"));
  EXPECT_FALSE(cli_arguments_allowed("run\ntiny.lua\n--seconds\ninf"));
}

}  // namespace
