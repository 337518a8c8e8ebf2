// Save files and replays (runtime/save_file.hpp, runtime/replay.hpp, `alloy
// run --save / --save-every / --record`, `alloy run FILE`, `alloy check
// FILE`, `alloy replay FILE`): round trips, continues that are bit for bit
// the uninterrupted run, hostile files (each exit 2, a clear message, no file
// written), a writer killed mid-write, and replays that diverge on purpose.
#include "runtime/save_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "apps/alloy/commands.hpp"
#include "lua/scene_loader.hpp"
#include "resolvers/plugins.hpp"
#include "runtime/replay.hpp"
#include "runtime/state_hash.hpp"
#include "runtime/world.hpp"
#include "tests/apps/cli_runner.hpp"

namespace fs = std::filesystem;

namespace alloy {
namespace {

using app::cli_test::cli;
using app::cli_test::Result;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

/// A fresh folder per test.
fs::path temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path d = fs::temp_directory_path() /
               ("alloy_save_test_" + std::to_string(::getpid()) + "_" + info->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir))
    names.insert(e.path().filename().string() + ":" +
                 std::to_string(e.is_regular_file() ? e.file_size() : 0));
  return names;
}

std::string scene_path(const std::string& name) {
  return std::string(ALLOY_SOURCE_DIR) + "/mods/" + name;
}

struct Scene {
  explicit Scene(const std::string& name) {
    register_native_plugins(registry);
    loaded = lua::load_scene(scene_path(name), registry);
  }
  World& world() { return *loaded.world; }
  PluginRegistry registry;
  lua::LoadedScene loaded;
};

SaveMeta meta_of(Scene& s, const std::string& name) {
  SaveMeta m = describe_world(s.world());
  m.scene = scene_path(name);
  m.scene_name = name;
  m.mods = {{name, "0.1.0"}};
  return m;
}

/// The hash after every step from `from` to `to`, continuing `world`.
std::vector<std::string> hashes(World& world, std::uint64_t to) {
  std::vector<std::string> out;
  while (world.step_count() < to) {
    world.step();
    out.push_back(std::to_string(world.step_count()) + " " + hex(hash_state(world).world));
  }
  return out;
}

/// Saves `name` at step `at` through a file's bytes, restores it in a new
/// world and checks every step to `to` against the uninterrupted run.
void expect_continue_identical(const std::string& name, std::uint64_t at, std::uint64_t to) {
  Scene a(name);
  a.world().run(at);
  SaveData d;
  d.meta = meta_of(a, name);
  d.snapshot = a.world().snapshot();
  const std::string bytes = encode_save(d);
  const auto straight = hashes(a.world(), to);

  Scene b(name);
  SaveData back = decode_save(bytes, "test");
  b.world().restore(back.snapshot);
  EXPECT_EQ(hex(hash_state(b.world()).world), hex(hash_state(d.snapshot).world))
      << name << ": the restored world is not the saved one";
  EXPECT_EQ(hashes(b.world(), to), straight) << name << " saved at step " << at;
}

// --- round trips and continues ------------------------------------------------------

TEST(SaveFile, SpaceContinuesBitForBitThroughAFile) {
  expect_continue_identical("space", 40, 120);
  expect_continue_identical("space", 0, 30);  // a save before the first step
}

TEST(SaveFile, EncodingIsStableAndEveryPartComesBack) {
  Scene a("space");
  a.world().run(25);
  SaveData d;
  d.meta = meta_of(a, "space");
  d.snapshot = a.world().snapshot();
  d.snapshot.inputs.push_back({3.5, a.world().find("probe"), "velocity", Vec3{1, 2, 3}});
  d.snapshot.swaps.push_back({4.0, "orbit", "gravity.nbody", "gravity.uniform"});
  const std::string bytes = encode_save(d);
  const SaveData back = decode_save(bytes, "test");
  EXPECT_EQ(encode_save(back), bytes);  // nothing lost, nothing added
  EXPECT_EQ(hash_state(back.snapshot).world, hash_state(d.snapshot).world);
  ASSERT_EQ(back.snapshot.inputs.size(), d.snapshot.inputs.size());
  EXPECT_EQ(back.snapshot.inputs.back().property, "velocity");
  EXPECT_EQ(std::get<Vec3>(back.snapshot.inputs.back().value).z, 3.0);
  ASSERT_EQ(back.snapshot.swaps.size(), d.snapshot.swaps.size());
  EXPECT_EQ(back.snapshot.swaps.back().to, "gravity.uniform");
  EXPECT_EQ(back.meta.mods.size(), 1u);
  EXPECT_EQ(back.meta.properties.size(), a.world().properties().size());
}

TEST(SaveFile, DoorbellFullSaveIsUnder50KBAndCompressed) {
  Scene a("doorbell");
  a.world().run(240);
  SaveData d;
  d.meta = meta_of(a, "doorbell");
  d.snapshot = a.world().snapshot();
  const std::string bytes = encode_save(d);
  EXPECT_LT(bytes.size(), 50u * 1024) << "a full save of the doorbell";
  const SaveContainer c = unpack_save(bytes, "test");
  std::uint32_t flags;
  std::memcpy(&flags, bytes.data() + 12, 4);
  EXPECT_EQ(flags & 1, 1u) << "zstd pays on a doorbell save";
  EXPECT_LT(bytes.size(), c.body.size());
}

// The doorbell and the motor through a file: the rigid body's contacts and
// the coil currents travel in SSTA, the restore's resync flag in STEP.
TEST(SaveFile, DoorbellContinuesBitForBit) {
  expect_continue_identical("doorbell", 120, 300);
}
TEST(SaveFile, MotorContinuesBitForBit) {
  expect_continue_identical("motor", 120, 300);
}

TEST(SaveCli, SaveThenContinueIsTheUninterruptedRun) {
  const fs::path dir = temp_dir();
  const std::string save = (dir / "space.alloysave").string();
  const Result first = cli({"run", "mods/space", "--steps", "40", "--quiet", "--save", save});
  ASSERT_EQ(first.code, 0) << first.err;
  const Result cont = cli({"run", save, "--steps", "80", "--quiet", "--hash"});
  ASSERT_EQ(cont.code, 0) << cont.err;
  const Result straight = cli({"run", "mods/space", "--steps", "120", "--quiet", "--hash"});
  ASSERT_EQ(straight.code, 0) << straight.err;
  EXPECT_NE(cont.out.find("state hash at step 120:"), std::string::npos) << cont.out;
  EXPECT_EQ(cont.out, straight.out);
  const Result ok = cli({"check", save});
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_NE(ok.out.find(": ok (save of 'space' at step 40"), std::string::npos) << ok.out;
}

TEST(SaveCli, SaveEveryWritesContinuableSaves) {
  const fs::path dir = temp_dir();
  const Result r =
      cli({"run", "mods/space", "--steps", "96", "--quiet", "--save-every", "0.1", dir.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  ASSERT_EQ(names.size(), 4u);  // at 0.1, 0.2, 0.3, 0.4 s = steps 24, 48, 72, 96
  EXPECT_EQ(names[0], "step-00000024.alloysave");
  EXPECT_EQ(names[3], "step-00000096.alloysave");
  const Result cont = cli({"run", (dir / names[1]).string(), "--steps", "48", "--quiet", "--hash"});
  const Result straight = cli({"run", "mods/space", "--steps", "96", "--quiet", "--hash"});
  ASSERT_EQ(cont.code, 0) << cont.err;
  EXPECT_EQ(cont.out, straight.out);
}

TEST(SaveCli, ContinueRefusesAnotherTimeStep) {
  const fs::path dir = temp_dir();
  const std::string save = (dir / "s").string();
  ASSERT_EQ(cli({"run", "mods/space", "--steps", "5", "--quiet", "--save", save}).code, 0);
  const Result r = cli({"run", save, "--steps", "5", "--dt", "0.001"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--dt"), std::string::npos) << r.err;
}

// --- hostile files -------------------------------------------------------------------

/// A valid save of space at step 20, as bytes, with its parts for rewriting.
struct Valid {
  Valid() : scene("space") {
    scene.world().run(20);
    data.meta = meta_of(scene, "space");
    data.snapshot = scene.world().snapshot();
    bytes = encode_save(data);
  }
  Scene scene;
  SaveData data;
  std::string bytes;
};

/// Each hostile file: `alloy check` and `alloy run` exit 2, with the message,
/// and the folder is as it was (nothing written, no temporary file).
/// `reader`: whether the file alone is wrong (else only the world it is
/// restored into tells: a mod or a property it lacks).
void expect_refused(const std::string& bytes, const std::string& message,
                    const std::string& name = "bad.alloysave", bool reader = true) {
  const fs::path dir = temp_dir();
  const fs::path file = dir / name;
  spit(file, bytes);
  const auto before = listing(dir);
  for (const std::string cmd : {"check", "run"}) {
    const Result r = cmd == std::string("run")
                         ? cli({"run", file.string(), "--steps", "3", "--quiet", "--save",
                                (dir / "out.alloysave").string()})
                         : cli({cmd, file.string()});
    // A file neither its name nor its magic marks as a save is a scene to
    // `run` and `check`: it fails as one. Either way exit 2.
    EXPECT_EQ(r.code, 2) << cmd << ": " << r.out << r.err;
    if (is_save_file(file.string())) {
      EXPECT_NE(r.err.find(message), std::string::npos) << cmd << ": " << r.err;
    }
    EXPECT_EQ(r.err.find("failure"), std::string::npos) << r.err;
  }
  EXPECT_EQ(listing(dir), before) << "something was written";
  EXPECT_EQ(cli({"replay", file.string()}).code, 2);
  if (!reader) return;
  // The reader itself refuses it the same way.
  try {
    read_save_file(file.string());
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
  }
}

std::string rewrap(const std::string& bytes, const std::function<void(SaveContainer&)>& edit) {
  SaveContainer c = unpack_save(bytes, "test");
  edit(c);
  return pack_save(c);
}

/// Offsets of each section in a block: tag position and size.
std::vector<std::pair<std::string, std::size_t>> sections(const std::string& block) {
  std::vector<std::pair<std::string, std::size_t>> out;
  std::size_t at = 0;
  while (at + 12 <= block.size()) {
    std::uint64_t size;
    std::memcpy(&size, block.data() + at + 4, 8);
    out.emplace_back(block.substr(at, 4), at);
    at += 12 + size;
  }
  return out;
}

TEST(HostileSave, EmptyFile) {
  expect_refused("", "the file is empty");
}

TEST(HostileSave, AFolder) {
  const fs::path dir = temp_dir();
  fs::create_directories(dir / "save.alloysave");
  try {
    read_save_file((dir / "save.alloysave").string());
    FAIL() << "a folder read as a save";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is a folder"), std::string::npos) << e.what();
  }
  const Result r = cli({"replay", (dir / "save.alloysave").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is a folder"), std::string::npos) << r.err;
  // --save onto a folder is refused before the run.
  const Result w =
      cli({"run", "mods/space", "--steps", "2", "--save", (dir / "save.alloysave").string()});
  EXPECT_EQ(w.code, 2);
  EXPECT_NE(w.err.find("it is a folder"), std::string::npos) << w.err;
}

TEST(HostileSave, AFileOfAnotherFormat) {
  expect_refused("RIFF\x24\x00\x00\x00WAVEfmt a sound file, not a save", "not an alloy save file",
                 "sound.wav");
}

TEST(HostileSave, ASaveOfAnotherProgram) {
  Valid v;
  v.data.meta.program = "blender";
  expect_refused(encode_save(v.data), "a save of the program 'blender'");
}

TEST(HostileSave, ANewerFormatVersion) {
  Valid v;
  expect_refused(rewrap(v.bytes, [](SaveContainer& c) { c.format = kSaveFormat + 1; }),
                 "is newer than this alloy reads");
}

TEST(HostileSave, AWrongChecksum) {
  Valid v;
  std::string b = v.bytes;
  b[40] ^= 0x01;
  expect_refused(b, "the checksum does not match");
}

TEST(HostileSave, FlippedBytesAnywhere) {
  Valid v;
  // In the meta block, in the body, and the last byte.
  for (std::size_t at : {std::size_t(60), v.bytes.size() / 2, v.bytes.size() - 1}) {
    std::string b = v.bytes;
    b[at] ^= 0x40;
    try {
      decode_save(b, "x");
      FAIL() << "flipped byte at " << at << " not noticed";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
    }
  }
  std::string b = v.bytes;
  b[v.bytes.size() / 3] ^= 0x01;
  expect_refused(b, "checksum");
}

TEST(HostileSave, TruncatedAtEachSection) {
  Valid v;
  const SaveContainer c = unpack_save(v.bytes, "test");
  const auto body = sections(c.body);
  ASSERT_EQ(body.size(), 11u);  // STEP OBJS COLS FRZN AREA STGS SSTA MSTA INPT SWAP END
  // The file cut short anywhere: the header's sizes say so.
  for (std::size_t cut : {std::size_t(47), std::size_t(48 + 10), v.bytes.size() - 9}) {
    try {
      decode_save(v.bytes.substr(0, cut), "x");
      FAIL() << "cut at " << cut;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
  }
  // A body cut at the start of each section, and inside each, with a valid
  // checksum (a writer that lied): the reader names the section.
  for (const auto& [tag, at] : body) {
    for (std::size_t extra : {std::size_t(0), std::size_t(13)}) {
      if (at + extra >= c.body.size()) continue;  // END is 12 bytes
      const std::string bad = rewrap(
          v.bytes, [&](SaveContainer& k) { k.body.resize(std::min(k.body.size(), at + extra)); });
      try {
        decode_save(bad, "x");
        ADD_FAILURE() << "body cut in section " << tag << " + " << extra;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'" + tag + "'"), std::string::npos)
            << tag << ": " << e.what();
      }
    }
  }
  expect_refused(rewrap(v.bytes, [&](SaveContainer& k) { k.body.resize(body[2].second + 20); }),
                 "section 'COLS'");
  // The meta block cut at each of its sections.
  for (const auto& [tag, at] : sections(c.meta)) {
    const std::string bad = rewrap(v.bytes, [&](SaveContainer& k) { k.meta.resize(at + 14); });
    EXPECT_THROW(decode_save(bad, "x"), InputError) << tag;
  }
}

TEST(HostileSave, AbsurdCounts) {
  Valid v;
  const auto body = sections(unpack_save(v.bytes, "t").body);
  // The slot count of OBJS (its first u64) set to 2^60.
  const std::string bad = rewrap(v.bytes, [&](SaveContainer& k) {
    const std::uint64_t n = 1ull << 60;
    std::memcpy(k.body.data() + body[1].second + 12, &n, 8);
  });
  expect_refused(bad, "a count of 1152921504606846976 slots is more than");
  // A section claiming more bytes than the body holds.
  const std::string big = rewrap(v.bytes, [&](SaveContainer& k) {
    const std::uint64_t n = ~0ull;
    std::memcpy(k.body.data() + body[3].second + 4, &n, 8);
  });
  expect_refused(big, "section 'FRZN' claims");
  // A header claiming a body of 16 EiB.
  std::string huge = v.bytes;
  const std::uint64_t n = 1ull << 62;
  std::memcpy(huge.data() + 32, &n, 8);
  expect_refused(huge, "more than the 1073741824 a save may hold");
}

TEST(HostileSave, AMissingMod) {
  Valid v;
  v.data.meta.mods.push_back({"ghost_mod", "2.1.0"});
  expect_refused(encode_save(v.data), "the save needs mod 'ghost_mod' (version 2.1.0)",
                 "bad.alloysave", false);
}

TEST(HostileSave, APropertyWhoseKindChanged) {
  Valid v;
  // "mass" saved as an integer property: the registry says number now.
  for (auto& p : v.data.meta.properties)
    if (p.name == "mass") p.kind = PropertyKind::Integer;
  for (auto& c : v.data.snapshot.columns)
    if (c.property == "mass") {
      const auto present = c.values->presence();
      c.kind = PropertyKind::Integer;
      c.values =
          Column<std::int64_t>::detached(0, std::vector<std::int64_t>(present.size(), 7),
                                         std::vector<std::uint8_t>(present.begin(), present.end()));
    }
  expect_refused(encode_save(v.data), "property 'mass' is integer in the save and number now",
                 "bad.alloysave", false);
}

TEST(HostileSave, AnUnknownPropertyWithValues) {
  Valid v;
  v.data.meta.properties.push_back({"mana_flux", PropertyKind::Number, {}});
  const auto slots = v.data.snapshot.objects.generations.size();
  std::vector<std::uint8_t> present(slots, 0);
  present[0] = 1;
  v.data.snapshot.columns.push_back(
      {"mana_flux", PropertyKind::Number,
       Column<double>::detached(0, std::vector<double>(slots, 1.0), present)});
  std::sort(v.data.snapshot.columns.begin(), v.data.snapshot.columns.end(),
            [](const auto& a, const auto& b) { return a.property < b.property; });
  expect_refused(encode_save(v.data), "the save holds values of property 'mana_flux'",
                 "bad.alloysave", false);
}

TEST(HostileSave, ASectionOutOfOrder) {
  Valid v;
  const std::string bad =
      rewrap(v.bytes, [](SaveContainer& k) { std::memcpy(k.body.data(), "OBJS", 4); });
  expect_refused(bad, "expected section 'STEP', found 'OBJS'");
}

TEST(HostileSave, BytesAfterTheEnd) {
  Valid v;
  expect_refused(rewrap(v.bytes, [](SaveContainer& k) { k.body += "tail"; }),
                 "bytes after the section 'END '");
}

TEST(HostileSave, AColumnThatDoesNotCoverTheObjects) {
  Valid v;
  for (auto& c : v.data.snapshot.columns)
    if (c.property == "mass") {
      const std::size_t n = c.values->presence().size() + 3;
      c.values = Column<double>::detached(0, std::vector<double>(n), std::vector<std::uint8_t>(n));
    }
  expect_refused(encode_save(v.data), "column 'mass' covers");
}

TEST(HostileSave, ADamagedCompressedBodyWithAValidChecksum) {
  Valid v;
  std::string b = v.bytes;
  std::uint64_t meta;
  std::memcpy(&meta, b.data() + 16, 8);
  b[48 + meta + 20] ^= 0x55;  // inside the zstd frame
  // Sealed again as the writer seals: XXH3 of the first 40 bytes, the meta
  // block and the stored body.
  const std::string covered = b.substr(0, 40) + b.substr(48);
  const std::uint64_t h = XXH3_64bits(covered.data(), covered.size());
  std::memcpy(b.data() + 40, &h, 8);
  expect_refused(b, "the compressed body");
}

TEST(HostileSave, AFrozenObjectThatIsNotAlive) {
  Valid v;
  v.data.snapshot.frozen.push_back({999, 1});
  expect_refused(encode_save(v.data), "frozen object #999 is not alive");
}

TEST(HostileSave, ASceneThatIsGone) {
  Valid v;
  v.data.meta.scene = "/nonexistent/scene/folder";
  expect_refused(encode_save(v.data), "the save's scene '/nonexistent/scene/folder' is not found",
                 "bad.alloysave", false);
}

TEST(HostileSave, ARecordingIsNotASaveAndBack) {
  const fs::path dir = temp_dir();
  const std::string rec = (dir / "r").string(), save = (dir / "s").string();
  ASSERT_EQ(
      cli({"run", "mods/space", "--steps", "3", "--quiet", "--record", rec, "--save", save}).code,
      0);
  const Result a = cli({"run", rec, "--steps", "2"});
  EXPECT_EQ(a.code, 2);
  EXPECT_NE(a.err.find("is a recording"), std::string::npos) << a.err;
  const Result b = cli({"replay", save});
  EXPECT_EQ(b.code, 2);
  EXPECT_NE(b.err.find("is a save, not a recording"), std::string::npos) << b.err;
}

TEST(HostileSave, AnEnumIndexOutOfRange) {
  Valid v;
  // An enum property with one value, carried by object 0 with index 5.
  v.data.meta.properties.push_back({"zz_mode", PropertyKind::Enum, {"only"}});
  const auto slots = v.data.snapshot.objects.generations.size();
  std::vector<std::uint8_t> present(slots, 0);
  present[0] = 1;
  v.data.snapshot.columns.push_back(
      {"zz_mode", PropertyKind::Enum,
       Column<EnumValue>::detached(0, std::vector<EnumValue>(slots, EnumValue{5}), present)});
  expect_refused(encode_save(v.data), "has enum index 5, it has 1 values");
}

// A recording whose log schedules an input at a negative time, and one whose
// log holds an input of a kind this build does not know: each refused.
TEST(HostileSave, AScheduledInputAtANegativeTime) {
  Valid v;
  v.data.meta.kind = "replay";
  ReplayInput in;
  in.step = v.data.snapshot.step;
  in.kind = ReplayInput::Kind::Schedule;
  in.id = v.scene.world().find("probe");
  in.property = "mass";
  in.value = 2.0;
  in.time = -1;
  v.data.inputs.push_back(in);
  expect_refused(encode_save(v.data), "an input scheduled at -1");
}
TEST(HostileSave, AnInputOfAnUnknownKind) {
  Valid v;
  v.data.meta.kind = "replay";
  ReplayInput in;
  in.step = v.data.snapshot.step;
  in.kind = ReplayInput::Kind(15);
  v.data.inputs.push_back(in);
  expect_refused(encode_save(v.data), "an input of unknown kind 15");
}

// --- atomic writes -------------------------------------------------------------------

TEST(SaveFile, AWriterKilledMidWriteLeavesThePreviousFile) {
  const fs::path dir = temp_dir();
  const std::string path = (dir / "world.alloysave").string();
  Valid v;
  write_save_file(path, v.data);
  const std::string before = slurp(path);
  // A bigger file (incompressible noise in a stage state), written in small
  // chunks by a child killed after its first chunk.
  SaveData big = v.data;
  std::vector<std::byte> noise(256 * 1024);
  std::uint64_t x = 88172645463325252ull;
  for (auto& b : noise) x ^= x << 13, x ^= x >> 7, x ^= x << 17, b = std::byte(x);
  big.snapshot.stage_states.push_back({"noise", noise});
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    WriteHooks hooks;
    hooks.chunk = 4096;
    hooks.after_chunk = [](std::size_t) { ::kill(::getpid(), SIGKILL); };
    try {
      write_save_file(path, big, hooks);
    } catch (...) {
    }
    ::_exit(0);  // not reached: killed
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the writer was not killed";
  EXPECT_EQ(slurp(path), before) << "the previous save was touched";
  EXPECT_NO_THROW(read_save_file(path));
  const fs::path tmp = path + ".tmp." + std::to_string(child);
  ASSERT_TRUE(fs::exists(tmp)) << "the killed writer wrote no temporary file?";
  EXPECT_EQ(fs::file_size(tmp), 4096u);
  // The next write to the path goes through and removes the dead writer's
  // temporary file (its process is gone); a live writer's file stays.
  const fs::path live = path + ".tmp." + std::to_string(::getppid());
  std::ofstream(live) << "a writer still at work";
  const fs::path other = (dir / "other.alloysave.tmp.").string() + std::to_string(child);
  std::ofstream(other) << "another file's";
  write_save_file(path, big);
  EXPECT_EQ(read_save_file(path).snapshot.stage_states.back().bytes.size(), noise.size());
  EXPECT_FALSE(fs::exists(tmp)) << "the killed writer's temporary file is still there";
  EXPECT_TRUE(fs::exists(live)) << "a live process's temporary file was removed";
  EXPECT_TRUE(fs::exists(other)) << "another save's temporary file was removed";
}

// --- replays -------------------------------------------------------------------------

/// Records `steps` steps of space in-process.
SaveData record_space(std::uint64_t steps, const std::function<void(World&)>& between = {}) {
  Scene s("space");
  Recorder rec(s.world(), meta_of(s, "space"));
  for (std::uint64_t i = 0; i < steps; ++i) {
    if (between) between(s.world());
    s.world().step();
  }
  return decode_save(encode_save(rec.data()), "recording");
}

struct Rebuild {
  std::optional<Scene> scene;
  World& operator()() {
    scene.reset();
    scene.emplace("space");
    return scene->world();
  }
};

TEST(Replay, AnUntouchedRunIsIdentical) {
  const SaveData rec = record_space(60);
  ASSERT_EQ(rec.hashes.size(), 60u);
  Rebuild rebuild;
  const ReplayResult r = replay(rec, std::ref(rebuild));
  EXPECT_TRUE(r.identical) << r.message();
  EXPECT_EQ(r.message(), "identical through step 60");
}

TEST(Replay, APerturbedRunNamesTheStepTheStageAndTheObject) {
  const SaveData rec = record_space(60);
  Rebuild rebuild;
  ReplayOptions o;
  // At step 37, right after the rigid body, the crate is nudged by 1e-9 m.
  o.tamper = [](World& w, std::uint64_t step, const std::string& stage) {
    if (step != 37 || stage != "rigid_body") return;
    const ObjectId crate = w.find("crate");
    Vec3 p = *w.value<Vec3>(crate, "position");
    p.x += 1e-9;
    w.set(crate, "position", p);
  };
  const ReplayResult r = replay(rec, std::ref(rebuild), o);
  ASSERT_FALSE(r.identical);
  EXPECT_EQ(r.step, 37u);
  EXPECT_EQ(r.stage, "rigid_body");
  EXPECT_EQ(r.steps, 36u);
  EXPECT_NE(std::find(r.properties.begin(), r.properties.end(), "position"), r.properties.end());
  ASSERT_EQ(r.objects.size(), 1u) << r.message();
  EXPECT_NE(r.objects[0].find("crate"), std::string::npos) << r.objects[0];
  const std::string m = r.message();
  EXPECT_NE(m.find("differs at step 37, first after stage 'rigid_body'"), std::string::npos) << m;
  EXPECT_NE(m.find("crate"), std::string::npos) << m;
}

TEST(Replay, APerturbationAfterALaterStageIsNamed) {
  const SaveData rec = record_space(20);
  // The stages after the rigid body in space's run order.
  std::vector<std::string> order;
  for (const auto& [stage, h] : rec.hashes[5].stages) order.push_back(stage);
  ASSERT_GE(order.size(), 2u);
  const std::string last = order.back();
  Rebuild rebuild;
  ReplayOptions o;
  o.tamper = [&](World& w, std::uint64_t step, const std::string& stage) {
    if (step == 6 && stage == last) w.set(w.find("probe"), "mass", 123.0);
  };
  const ReplayResult r = replay(rec, std::ref(rebuild), o);
  ASSERT_FALSE(r.identical);
  EXPECT_EQ(r.step, 6u);
  EXPECT_EQ(r.stage, last);
  EXPECT_NE(std::find(r.properties.begin(), r.properties.end(), "mass"), r.properties.end());
}

TEST(Replay, EditsFromOutsideAreReplayed) {
  const SaveData rec = record_space(30, [](World& w) {
    if (w.step_count() == 10) w.set(w.find("probe"), "velocity", Vec3{0.5, 0, 0});
  });
  ASSERT_EQ(rec.inputs.size(), 1u);
  EXPECT_EQ(rec.inputs[0].step, 10u);
  Rebuild rebuild;
  EXPECT_TRUE(replay(rec, std::ref(rebuild)).identical);
  // Without the edit the replay parts at step 11, in the probe.
  SaveData without = rec;
  without.inputs.clear();
  const ReplayResult r = replay(without, std::ref(rebuild));
  ASSERT_FALSE(r.identical);
  EXPECT_EQ(r.step, 11u);
  EXPECT_NE(r.message().find("probe"), std::string::npos) << r.message();
}

// Every kind of input the world tells its observer, made straight on the
// world (as the viewer makes them), with no call to the recorder: a box
// created and shaped, a property removed, an object destroyed, an undo (a
// restore of an earlier snapshot, which sends the step count back), a sync
// and a swap. The replay, read back from the file's bytes, is identical; the
// log holds each kind.
SaveData record_an_edit_session() {
  // By the count of steps recorded, not the world's step count, which the
  // undo sends back.
  Snapshot undo;  // the world as it was before the box
  return record_space(60, [&undo, k = 0](World& w) mutable {
    switch (k++) {
      case 5: {
        undo = w.snapshot();
        const ObjectId box = w.create("box");
        w.set(box, "shape",
              w.properties().enum_value(*w.properties().find("shape"), "box").value());
        w.set(box, "size", Vec3{0.1, 0.1, 0.1});
        w.set(box, "position", Vec3{0.3, 6.4, 0});
        w.set(box, "mass", 0.5);
        w.sync();
        break;
      }
      case 12:
        w.remove(w.find("probe"), "restitution");
        break;
      case 20:
        w.destroy(w.find("box"));
        break;
      case 25:
        w.restore(undo);  // back to step 5: the step count goes back too
        break;
      case 30:
        w.swap("orbit", "gravity.nbody", "gravity.uniform");
        break;
      default:
        break;
    }
  });
}

TEST(Replay, EveryKindOfInputFromOutsideIsHeardAndReplayed) {
  const SaveData rec = record_an_edit_session();
  std::set<ReplayInput::Kind> kinds;
  for (const auto& in : rec.inputs) kinds.insert(in.kind);
  for (const auto k : {ReplayInput::Kind::Create, ReplayInput::Kind::Set, ReplayInput::Kind::Sync,
                       ReplayInput::Kind::Remove, ReplayInput::Kind::Destroy,
                       ReplayInput::Kind::Restore, ReplayInput::Kind::Swap})
    EXPECT_TRUE(kinds.contains(k)) << "no input of kind " << int(k) << " was logged";
  ASSERT_EQ(rec.hashes.size(), 60u);
  // The undo at step 25 sent the world back to step 5: 60 steps end at 40.
  EXPECT_EQ(rec.hashes.back().step, 40u);
  Rebuild rebuild;
  const ReplayResult r = replay(rec, std::ref(rebuild));
  EXPECT_TRUE(r.identical) << r.message();
  EXPECT_EQ(r.message(), "identical through step 40");
}

// The same session with the box's mass changed after the rigid body's
// advance of its 9th step: the replay names the step, the stage and the
// property, and the box.
TEST(Replay, ADivergenceInAnEditSessionIsNamed) {
  const SaveData rec = record_an_edit_session();
  Rebuild rebuild;
  ReplayOptions o;
  o.tamper = [](World& w, std::uint64_t step, const std::string& stage) {
    if (step == 9 && stage == "rigid_body") w.set(w.find("box"), "mass", 0.25);
  };
  const ReplayResult r = replay(rec, std::ref(rebuild), o);
  ASSERT_FALSE(r.identical);
  EXPECT_EQ(r.step, 9u);
  EXPECT_EQ(r.stage, "rigid_body");
  EXPECT_NE(std::find(r.properties.begin(), r.properties.end(), "mass"), r.properties.end())
      << r.message();
  EXPECT_NE(r.message().find("box"), std::string::npos) << r.message();
  // Without the logged restore the replay cannot follow the recording past
  // the undo: it says so, naming the steps, rather than comparing others.
  SaveData without = rec;
  std::erase_if(without.inputs,
                [](const ReplayInput& in) { return in.kind == ReplayInput::Kind::Restore; });
  try {
    const ReplayResult w = replay(without, std::ref(rebuild));
    FAIL() << "a replay without the undo went through: " << w.message();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("step 26 ran where it has step 6"), std::string::npos)
        << e.what();
  }
}

/// Records `steps` steps of `name` in-process, calling `between` before each.
SaveData record_scene(const std::string& name, std::uint64_t steps,
                      const std::function<void(World&)>& between) {
  Scene s(name);
  Recorder rec(s.world(), meta_of(s, name));
  for (std::uint64_t i = 0; i < steps; ++i) {
    between(s.world());
    s.world().step();
  }
  return decode_save(encode_save(rec.data()), "recording");
}

struct RebuildScene {
  std::string name;
  std::optional<Scene> scene;
  World& operator()() {
    scene.reset();
    scene.emplace(name);
    return scene->world();
  }
};

/// The recording without its inputs of kind `k`.
SaveData without_kind(SaveData d, ReplayInput::Kind k) {
  std::erase_if(d.inputs, [k](const ReplayInput& in) { return in.kind == k; });
  return d;
}

// schedule() and schedule_swap() called after recording began (a game's
// script, a tool) are inputs: logged with their time, made again by the
// replay (which then applies them when they come due, as the world did).
// Without them the replay parts at the step after each call.
TEST(Replay, ScheduleCallsAfterRecordingBeganAreReplayed) {
  const SaveData rec = record_scene("rigid_demo", 60, [](World& w) {
    if (w.step_count() == 10)
      w.schedule(20 * w.dt(), w.find("ball"), w.properties().id("velocity"), Vec3{0.7, 2.0, 0});
    if (w.step_count() == 12) w.schedule_swap(30 * w.dt(), "", "gravity.uniform", "gravity.nbody");
  });
  std::map<ReplayInput::Kind, const ReplayInput*> by_kind;
  for (const auto& in : rec.inputs) by_kind.emplace(in.kind, &in);
  ASSERT_TRUE(by_kind.contains(ReplayInput::Kind::Schedule)) << "the schedule() was not logged";
  ASSERT_TRUE(by_kind.contains(ReplayInput::Kind::ScheduleSwap))
      << "the schedule_swap() was not logged";
  EXPECT_EQ(by_kind[ReplayInput::Kind::Schedule]->step, 10u);
  EXPECT_EQ(by_kind[ReplayInput::Kind::Schedule]->time, 20 * (1.0 / 240));
  EXPECT_EQ(by_kind[ReplayInput::Kind::ScheduleSwap]->to, "gravity.nbody");
  RebuildScene rebuild{"rigid_demo"};
  const ReplayResult r = replay(rec, std::ref(rebuild));
  EXPECT_TRUE(r.identical) << r.message();
  EXPECT_EQ(r.message(), "identical through step 60");

  // Without them the replay parts at once: the state hash covers the
  // pending inputs and swaps (the schedule), so the step after each call.
  const ReplayResult a = replay(without_kind(rec, ReplayInput::Kind::Schedule), std::ref(rebuild));
  ASSERT_FALSE(a.identical);
  EXPECT_EQ(a.step, 11u) << a.message();
  const ReplayResult b =
      replay(without_kind(rec, ReplayInput::Kind::ScheduleSwap), std::ref(rebuild));
  ASSERT_FALSE(b.identical);
  EXPECT_EQ(b.step, 13u) << b.message();
}

// A viewer that draws contact forces demands impulses (World::demand_impulses):
// the demand changes what the contact set and the rigid body keep (impulse
// totals, whether impulses are known), so the state hash moves with it. It
// is an input: the replay makes it again and is identical; without it the
// replay parts at the first step with the demand. A demand held when
// recording begins is the recording's first input.
TEST(Replay, AnImpulseDemandFromOutsideIsReplayed) {
  auto demand = [](World& w) {
    if (w.step_count() == 5) w.demand_impulses(true);
    if (w.step_count() == 40) w.demand_impulses(false);
  };
  // The demand does change the hash (else this test could not fail).
  {
    Scene a("rigid_demo"), b("rigid_demo");
    bool differs = false;
    for (int i = 0; i < 60; ++i) {
      demand(a.world());
      a.world().step();
      b.world().step();
      differs = differs || hash_state(a.world()).world != hash_state(b.world()).world;
    }
    ASSERT_TRUE(differs) << "demanding impulses changed no state hash in rigid_demo";
  }
  const SaveData rec = record_scene("rigid_demo", 60, demand);
  ASSERT_EQ(std::count_if(
                rec.inputs.begin(), rec.inputs.end(),
                [](const ReplayInput& in) { return in.kind == ReplayInput::Kind::DemandImpulses; }),
            2);
  RebuildScene rebuild{"rigid_demo"};
  const ReplayResult r = replay(rec, std::ref(rebuild));
  EXPECT_TRUE(r.identical) << r.message();
  const ReplayResult d =
      replay(without_kind(rec, ReplayInput::Kind::DemandImpulses), std::ref(rebuild));
  ASSERT_FALSE(d.identical);
  EXPECT_EQ(d.step, 6u) << d.message();

  // Held before recording begins: logged as the first input.
  Scene s("rigid_demo");
  s.world().demand_impulses(true);
  s.world().run(3);
  Recorder held(s.world(), meta_of(s, "rigid_demo"));
  s.world().run(20);
  const SaveData h = decode_save(encode_save(held.data()), "recording");
  ASSERT_FALSE(h.inputs.empty());
  EXPECT_EQ(h.inputs[0].kind, ReplayInput::Kind::DemandImpulses);
  EXPECT_TRUE(replay(h, std::ref(rebuild)).identical);
}

TEST(ReplayCli, RecordThenReplay) {
  const fs::path dir = temp_dir();
  const std::string rec = (dir / "space.alloyrec").string();
  const Result a = cli({"run", "mods/space", "--steps", "50", "--quiet", "--record", rec, "--swap",
                        "orbit:gravity.nbody=gravity.uniform@0.1"});
  ASSERT_EQ(a.code, 0) << a.err;
  const Result r = cli({"replay", rec});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("identical through step 50"), std::string::npos) << r.out;
  const SaveData d = read_save_file(rec);
  bool swapped = false;
  for (const auto& in : d.inputs) swapped |= in.kind == ReplayInput::Kind::Swapped;
  EXPECT_TRUE(swapped) << "the --swap was not logged";
  const Result c = cli({"check", rec});
  EXPECT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("50 recorded steps"), std::string::npos) << c.out;
}

}  // namespace
}  // namespace alloy
