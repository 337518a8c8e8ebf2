// Tests for the viewer as an editor (issue 17): New, Save as, undo and redo
// of every kind of edit, the hinge, glue and string tools, the resize
// handle, the inspector's edits, and a lever built from an empty board by a
// script that `alloy run` then runs the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>

#include "apps/viewer/input_script.hpp"
#include "apps/viewer/viewer.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "runtime/replay.hpp"
#include "runtime/save_file.hpp"
#include "runtime/state_hash.hpp"
#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

namespace fs = std::filesystem;

using test::click;
using test::entry;
using test::key;
using test::new_board;

std::uint64_t hash(Viewer& v) {
  return hash_state(*v.world()).world;
}

/// What differs between the world now and a hash taken before (for messages).
std::string differences(Viewer& v, const StateHash& then) {
  std::string out;
  for (const std::string& d : hash_differences(then, hash_state(*v.world()))) out += d + "; ";
  return out;
}

void drag(Viewer& v, Vec2 from, Vec2 to) {
  v.push_mouse(SDL_MOUSEMOTION, from);
  v.push_mouse(SDL_MOUSEBUTTONDOWN, from);
  v.frame();
  v.push_mouse(SDL_MOUSEMOTION, (from + to) * 0.5);
  v.frame();
  v.push_mouse(SDL_MOUSEMOTION, to);
  v.frame();
  v.push_mouse(SDL_MOUSEBUTTONUP, to);
  v.frame();
}

std::string all_messages(Viewer& v) {
  std::string s;
  for (const auto& m : v.messages()) s += m + "\n";
  return s;
}

/// Does `edit`, then checks that Ctrl+Z gives back the world's hash from
/// before and Ctrl+Y the one after, twice over.
void expect_undoable(Viewer& v, const std::string& what, const std::function<void()>& edit,
                     std::size_t records = 1) {
  SCOPED_TRACE(what);
  const StateHash before_full = hash_state(*v.world());
  const std::uint64_t before = before_full.world;
  const std::size_t depth = v.history().undo_depth();
  edit();
  v.frame();
  const StateHash after_full = hash_state(*v.world());
  const std::uint64_t after = after_full.world;
  ASSERT_NE(before, after) << what << " changed nothing";
  ASSERT_EQ(v.history().undo_depth(), depth + records) << what << " was not recorded as asked";
  for (std::size_t k = 1; k < records; ++k) key(v, SDLK_z, KMOD_LCTRL);
  for (std::size_t k = 1; k < records; ++k) key(v, SDLK_y, KMOD_LCTRL);
  ASSERT_EQ(hash(v), after) << "redo of the first steps of " << what;
  for (int round = 0; round < 2; ++round) {
    for (std::size_t k = 1; k < records; ++k) key(v, SDLK_z, KMOD_LCTRL);
    key(v, SDLK_z, KMOD_LCTRL);
    EXPECT_EQ(hash(v), before) << "undo of " << what << ": " << differences(v, before_full) << " / "
                               << all_messages(v);
    key(v, SDLK_y, KMOD_LCTRL);
    for (std::size_t k = 1; k < records; ++k) key(v, SDLK_y, KMOD_LCTRL);
    EXPECT_EQ(hash(v), after) << "redo of " << what << ": " << differences(v, after_full)
                              << all_messages(v);
  }
}

TEST(ViewerEditor, NewIsAnEmptyBoardWithAFloorAndUntitled) {
  auto v = new_board();
  ASSERT_TRUE(v->load_error().empty()) << v->load_error();
  EXPECT_TRUE(v->untitled());
  EXPECT_TRUE(bool(v->world()->find("floor")));
  EXPECT_EQ(read_parts(*v->world()).size(), 1u);
  EXPECT_FALSE(v->history().can_undo());
}

TEST(ViewerEditor, EveryKindOfEditIsUndoneAndRedoneToTheSameStateHash) {
  auto v = new_board();
  World& w = *v->world();
  expect_undoable(*v, "add a bar", [&] { v->drop_part(entry("steel bar"), {0, 0.3}); });
  const ObjectId bar = w.find("steel_bar");
  ASSERT_TRUE(bool(bar));
  expect_undoable(*v, "add a post", [&] { v->drop_part(entry("post"), {-0.2, 0.06}); });
  expect_undoable(*v, "move by the hand", [&] { drag(*v, {0.02, 0.3}, {0.1, 0.4}); });
  EXPECT_NEAR(test::position_of(w, "steel_bar").x, 0.08, 2e-3);  // to the pixel
  v->select(bar);
  expect_undoable(*v, "turn (E)", [&] { key(*v, SDLK_e); });
  expect_undoable(*v, "pin (P)", [&] { key(*v, SDLK_p); });
  key(*v, SDLK_p);  // unpinned again, itself an edit
  expect_undoable(*v, "hinge to the board", [&] {
    key(*v, SDLK_h);
    click(*v, {0.08, 0.4});
  });
  expect_undoable(
      *v, "glue",
      [&] {
        v->drop_part(entry("steel disk"), {-0.3, 0.5});
        key(*v, SDLK_j);
        click(*v, {-0.3, 0.5});
      },
      2);
  expect_undoable(*v, "string", [&] {
    key(*v, SDLK_t);
    click(*v, {-0.2, 0.1});
    click(*v, {-0.3, 0.5});
  });
  v->select(bar);
  v->frame();
  const auto handle = v->resize_handle();
  ASSERT_TRUE(handle);
  expect_undoable(*v, "resize by the handle", [&] { drag(*v, *handle, *handle + Vec2{0.05, 0}); });
  expect_undoable(*v, "set a property", [&] {
    v->edit("set", [&] { return v->editor().set_property(bar, "friction", 0.9); });
  });
  expect_undoable(*v, "material", [&] {
    v->edit("material", [&] { return v->editor().set_material(bar, "wood"); });
  });
  expect_undoable(
      *v, "battery and coil",
      [&] {
        v->drop_part(entry("battery"), {0.3, 0.2});
        v->drop_part(entry("coil"), {0.3, 0.5});
      },
      2);
  expect_undoable(*v, "wire", [&] {
    key(*v, SDLK_w);
    click(*v, {0.3 + 0.05, 0.2});
    click(*v, {0.3 - 0.02, 0.5});
  });
  v->select(bar);
  expect_undoable(*v, "remove (Delete)", [&] { key(*v, SDLK_DELETE); });
  expect_undoable(*v, "reset", [&] { v->reset(); });
  EXPECT_EQ(read_parts(*v->world()).size(), read_parts(*v->world()).size());
}

TEST(ViewerEditor, UndoWhileRunningTakesTheWorldBackToTheEdit) {
  auto v = new_board();
  v->set_paused(false);
  v->drop_part(entry("rubber ball"), {0, 0.5});
  const double t_edit = v->world()->time();
  for (int i = 0; i < 20; ++i) v->frame();
  ASSERT_GT(v->world()->time(), t_edit + 0.2);
  key(*v, SDLK_z, KMOD_LCTRL);
  EXPECT_FALSE(bool(v->world()->find("ball")));
  EXPECT_LE(v->world()->time(), t_edit + 1.0 / 30);
  key(*v, SDLK_y, KMOD_LCTRL);
  EXPECT_TRUE(bool(v->world()->find("ball")));
}

TEST(ViewerEditor, AHingeAtAPointJoinsTheTwoPartsThereAndTurnsAbout) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("post"), {0, 0.06});
  v->drop_part(entry("wooden plank"), {0.05, 0.13});
  v->drop_part(entry("steel disk"), {0.15, 0.165});
  key(*v, SDLK_h);
  click(*v, {0, 0.121});  // where the plank lies on the post
  const ObjectId hinge = w.find("hinge");
  ASSERT_TRUE(bool(hinge)) << (v->messages().empty() ? "" : v->messages().back());
  EXPECT_EQ(w.value<ObjectId>(hinge, "body_a"), w.find("plank"));
  EXPECT_EQ(w.value<ObjectId>(hinge, "body_b"), w.find("post"));
  EXPECT_EQ(v->selected(), hinge);
  // The disk on the long arm turns the plank clockwise about the hinge.
  v->set_paused(false);
  for (int i = 0; i < 30; ++i) v->frame();
  const Vec3 pivot = std::get<Vec3>(w.get(hinge, "anchor"));
  EXPECT_NEAR(pivot.x, 0, 2e-3);
  EXPECT_NEAR(pivot.y, 0.121, 2e-3);
  const double angle = angle_z(std::get<Quat>(w.get(w.find("plank"), "orientation")));
  EXPECT_LT(angle, -0.05);
  // A click on a pivot selects the joint; Delete removes it.
  v->set_paused(true);
  key(*v, SDLK_ESCAPE);
  click(*v, xy(pivot));
  EXPECT_EQ(v->selected(), hinge);
  key(*v, SDLK_DELETE);
  EXPECT_FALSE(w.store().alive(hinge));
}

TEST(ViewerEditor, AHingeOnEmptyBoardOrOnAStaticPartAloneIsRefused) {
  auto v = new_board();
  key(*v, SDLK_h);
  click(*v, {0.3, 0.5});
  EXPECT_NE(v->messages().back().find("goes through a part"), std::string::npos);
  key(*v, SDLK_h);
  click(*v, {0.3, -0.01});  // the floor alone
  EXPECT_NE(v->messages().back().find("static"), std::string::npos);
  EXPECT_FALSE(v->history().can_undo());
}

TEST(ViewerEditor, AStringHangsABallFromAPostAndHoldsIt) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("shelf"), {0, 0.4});
  v->drop_part(entry("rubber ball"), {0.0, 0.2});
  key(*v, SDLK_t);
  click(*v, {0.0, 0.39});
  click(*v, {0.0, 0.21});
  ASSERT_TRUE(bool(w.find("string"))) << v->messages().back();
  v->set_paused(false);
  for (int i = 0; i < 60; ++i) v->frame();
  // Without the string the ball would have fallen to the floor (y = 0.02).
  EXPECT_GT(test::position_of(w, "ball").y, 0.12);
}

TEST(ViewerEditor, TheResizeHandleGrowsABarAndItsMass) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("steel bar"), {0, 0.3});
  const ObjectId bar = w.find("steel_bar");
  const double m0 = std::get<double>(w.get(bar, "mass"));
  v->select(bar);
  v->frame();
  const Vec2 h = *v->resize_handle();
  EXPECT_NEAR(h.x, 0.075, 1e-9);
  drag(*v, h, {0.15, 0.31});
  const Vec3 size = std::get<Vec3>(w.get(bar, "size"));
  EXPECT_NEAR(size.x, 0.3, 2e-3);
  EXPECT_NEAR(size.y, 0.02, 2e-3);
  EXPECT_NEAR(std::get<double>(w.get(bar, "mass")), m0 * size.x * size.y / (0.15 * 0.01), 1e-9);
}

TEST(ViewerEditor, TheInspectorRefusesAValueOutOfRangeAndSaysTheRange) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("steel bar"), {0, 0.3});
  const ObjectId bar = w.find("steel_bar");
  const EditResult r = v->edit("set", [&] { return v->editor().set_property(bar, "mass", -1.0); });
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("steel_bar.mass"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("kg"), std::string::npos) << r.message;
  EXPECT_EQ(v->history().undo_depth(), 1u);  // the drop only
  const EditResult m = v->edit("mat", [&] { return v->editor().set_material(bar, "wood"); });
  ASSERT_TRUE(m.ok) << m.message;
  EXPECT_EQ(std::get<double>(w.get(bar, "density")), 700);
  EXPECT_NEAR(std::get<double>(w.get(bar, "mass")), 700 * 0.15 * 0.01 * 0.01, 1e-12);
  EXPECT_FALSE(w.value<bool>(bar, "conductive").has_value());
  EXPECT_FALSE(v->editor().set_material(bar, "cheese").ok);
}

TEST(ViewerEditor, ScriptKeysTakeModifiersAndPaletteEntriesByLabel) {
  const auto events = parse_script("1 key ctrl+shift+s\n2 palette steel bar\n3 text a.lua\n", "s");
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].key, "s");
  EXPECT_TRUE(events[0].ctrl);
  EXPECT_TRUE(events[0].shift);
  EXPECT_EQ(events[1].kind, ScriptEvent::Kind::Palette);
  EXPECT_EQ(events[1].key, "steel bar");
  EXPECT_EQ(events[2].kind, ScriptEvent::Kind::Text);
  EXPECT_THROW(parse_script("1 palette\n", "s"), InputError);
}

/// The lever of docs/kit.md: a post, a plank hinged on it, a disk glued to
/// its long arm, saved with Ctrl+Shift+S, all from a script.
std::string lever_script(const fs::path& save_to) {
  // The script docs/kit.md walks through, then Save as.
  std::ifstream in(test::source("tests/viewer/scripts/lever.script"));
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_FALSE(s.str().empty()) << "tests/viewer/scripts/lever.script not read";
  s << "22 key ctrl+shift+s\n24 text " << save_to.string() << "\n26 key Return\n";
  return s.str();
}

TEST(ViewerEditor, AScriptBuildsALeverOnAHingeFromAnEmptyBoardAndAlloyRunRunsItTheSame) {
  const fs::path dir = test::temp_dir();
  const fs::path saved = dir / "lever.lua";
  fs::remove(saved);
  ViewerOptions o = test::headless("");
  auto v = std::make_unique<Viewer>(o);
  v->add_script(parse_script(lever_script(saved), "lever.script"));
  for (int i = 0; i < 30; ++i) v->frame();
  ASSERT_TRUE(fs::exists(saved)) << (v->messages().empty() ? "" : v->messages().back());
  EXPECT_FALSE(v->untitled());
  EXPECT_FALSE(v->history().dirty());
  World& w = *v->world();
  ASSERT_TRUE(bool(w.find("hinge")));
  ASSERT_TRUE(bool(w.find("glue")));
  ASSERT_EQ(w.time(), 0);  // built paused: the file holds the world at t = 0
  {
    // The file holds the world as it is: the same state hash at t = 0.
    test::Loaded l0 = test::load(saved);
    l0.world().start();
    EXPECT_EQ(hex(hash_state(l0.world()).world), hex(hash_state(w).world));
  }
  // The viewer runs it for 0.5 s ...
  const int steps = int(std::lround(0.5 / w.dt()));
  for (int i = 0; i < steps; ++i) v->step_once();
  v->frame();
  ASSERT_EQ(w.step_count(), std::uint64_t(steps));
  const double angle = angle_z(std::get<Quat>(w.get(w.find("plank"), "orientation")));
  EXPECT_LT(angle, -0.1);  // the disk's side went down
  // ... and so does the saved scene loaded afresh: the same bits.
  test::Loaded l = test::load(saved);
  l.world().start();
  for (int i = 0; i < steps; ++i) l.world().step();
  EXPECT_EQ(hex(hash_state(l.world()).world), hex(hash_state(w).world));
#ifdef ALLOY_BINARY
  // And `alloy run`, the command a player would use.
  const std::string cmd = std::string(ALLOY_BINARY) + " run " + saved.string() + " --steps " +
                          std::to_string(steps) + " --hash --quiet 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  ASSERT_TRUE(pipe);
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  ::pclose(pipe);
  EXPECT_NE(out.find(hex(hash_state(w).world)), std::string::npos) << out;
#endif
}

}  // namespace
}  // namespace alloy::viewer

namespace alloy::viewer {
namespace {

TEST(ViewerEditor, NewAsksFirstWhenEditsAreNotSavedAndEscapeKeepsThem) {
  auto v = new_board();
  v->drop_part(entry("steel bar"), {0, 0.3});
  ASSERT_TRUE(v->history().dirty());
  key(*v, SDLK_n, KMOD_LCTRL);
  EXPECT_TRUE(bool(v->world()->find("steel_bar")));  // asked, not done
  key(*v, SDLK_ESCAPE);
  key(*v, SDLK_n, KMOD_LCTRL);  // asked again: the popup had closed
  EXPECT_TRUE(bool(v->world()->find("steel_bar")));
  key(*v, SDLK_RETURN);
  EXPECT_FALSE(bool(v->world()->find("steel_bar")));
  EXPECT_FALSE(v->history().can_undo());
  EXPECT_TRUE(v->untitled());
}

TEST(ViewerEditor, SaveOfAnUntitledBoardAsksForANameAndOpenLoadsIt) {
  auto v = new_board();
  v->drop_part(entry("rubber ball"), {0, 0.3});
  const fs::path file = test::temp_dir() / "ball.lua";
  fs::remove(file);
  key(*v, SDLK_s, KMOD_LCTRL);  // untitled: Save is Save as
  EXPECT_FALSE(fs::exists(file));
  v->add_script(parse_script("1 text " + file.string() + "\n3 key Return\n", "t"));
  for (int i = 0; i < 5; ++i) v->frame();  // the field takes the focus a frame after it opens
  ASSERT_TRUE(fs::exists(file)) << all_messages(*v);
  EXPECT_EQ(v->save_path(), file.string());
  EXPECT_FALSE(v->untitled());
  auto w = new_board();
  EXPECT_FALSE(w->open(test::temp_dir() / "no_such.lua"));
  EXPECT_TRUE(w->open(file));
  EXPECT_TRUE(bool(w->world()->find("ball")));
}

}  // namespace
}  // namespace alloy::viewer

namespace alloy::viewer {
namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The circuit of docs/kit.md, built by tests/viewer/scripts/circuit.script
/// from palette parts alone: a battery, a switch and a lamp in one loop.
std::unique_ptr<Viewer> palette_circuit() {
  auto v = std::make_unique<Viewer>(test::headless(""));
  const std::string script = read_text(test::source("tests/viewer/scripts/circuit.script"));
  EXPECT_FALSE(script.empty());
  v->add_script(parse_script(script, "circuit.script"));
  for (int i = 0; i < 31; ++i) v->frame();
  return v;
}

TEST(ViewerCircuit, APaletteLampOnAPaletteBatteryLightsAndAClickOnTheSwitchPutsItOut) {
  auto v = palette_circuit();
  World& w = *v->world();
  const ObjectId lamp = w.find("lamp"), sw = w.find("switch"), bat = w.find("battery");
  ASSERT_TRUE(lamp && sw && bat) << all_messages(*v);
  for (int i = 0; i < 20; ++i) v->step_once();
  v->frame();
  // 6 V over the 12 ohm filament (wires, switch and the battery's own
  // resistance take a little): about 0.5 A and 3 W, a few tens of lumens.
  const double i_lamp = std::abs(w.value<double>(lamp, "current").value_or(0));
  EXPECT_GT(i_lamp, 0.4) << all_messages(*v);
  EXPECT_LT(i_lamp, 0.51);
  EXPECT_GT(w.value<double>(lamp, "luminous_flux").value_or(0), 10.0);
  // A click (press and release without moving) on the switch opens it.
  const Vec2 at = test::position_of(w, "switch");
  std::ostringstream s;
  s << "1 press " << at.x << " " << at.y << "\n2 release " << at.x << " " << at.y << "\n";
  v->add_script(parse_script(s.str(), "click"));
  for (int i = 0; i < 4; ++i) v->frame();
  EXPECT_FALSE(w.value<bool>(sw, "switch_closed").value_or(true)) << all_messages(*v);
  for (int i = 0; i < 20; ++i) v->step_once();
  EXPECT_LT(std::abs(w.value<double>(lamp, "current").value_or(1)), 1e-6);
  EXPECT_LT(w.value<double>(lamp, "luminous_flux").value_or(1), 1e-3);
  // The click is an edit: undone, the switch is closed again.
  EXPECT_EQ(v->history().undo_what(), "switch switch");
}

// A junction from the palette joins wires in the middle of the board: two
// palette lamps fed through it from one battery share its current by
// Kirchhoff's current law, half each (they are equal), and each draws what
// the parallel circuit's resistances predict.
TEST(ViewerCircuit, TwoLampsFedThroughAPaletteJunctionShareTheBatterysCurrent) {
  auto v = std::make_unique<Viewer>(test::headless(""));
  const std::string script = read_text(test::source("tests/viewer/scripts/junction.script"));
  ASSERT_FALSE(script.empty());
  v->add_script(parse_script(script, "junction.script"));
  for (int i = 0; i < 43; ++i) v->frame();
  World& w = *v->world();
  const ObjectId bat = w.find("battery"), j = w.find("junction"), l1 = w.find("lamp"),
                 l2 = w.find("lamp_2");
  ASSERT_TRUE(bat && j && l1 && l2) << all_messages(*v);
  for (const char* n : {"wire", "wire_2", "wire_3", "wire_4", "wire_5"})
    ASSERT_TRUE(bool(w.find(n))) << n << " was not made: " << all_messages(*v);
  for (int i = 0; i < 20; ++i) v->step_once();
  auto amps = [&](ObjectId id) { return std::abs(w.value<double>(id, "current").value_or(0)); };
  auto ohms = [&](const char* n) { return w.value<double>(w.find(n), "resistance").value_or(0); };
  const double i1 = amps(l1), i2 = amps(l2), ib = amps(bat);
  EXPECT_GT(i1, 0.3) << all_messages(*v);
  EXPECT_NEAR(i1 + i2, ib, 1e-9 * ib) << "the lamps' currents do not add up to the battery's";
  EXPECT_NEAR(amps(j), ib, 1e-9 * ib) << "the battery's current does not all pass the junction";
  // The two branches (a wire to each lamp, the lamp, a wire back) in
  // parallel, in series with the battery's own resistance, its wire and
  // the junction; within 1 %, as the meter's test (the wires' ends take a
  // little more: 0.3 % here).
  const double b1 = ohms("wire_2") + ohms("lamp") + ohms("wire_4");
  const double b2 = ohms("wire_3") + ohms("lamp_2") + ohms("wire_5");
  const double r = w.value<double>(bat, "internal_resistance").value_or(0) + ohms("wire") +
                   ohms("junction") + b1 * b2 / (b1 + b2);
  const double emf = w.value<double>(bat, "emf").value_or(0);
  EXPECT_NEAR(ib, emf / r, 0.01 * emf / r);
  EXPECT_NEAR(i1 / i2, b2 / b1, 1e-6);
}

}  // namespace
}  // namespace alloy::viewer

namespace alloy::viewer {
namespace {

TEST(ViewerHelp, F1AndQuestionMarkToggleTheHelpOverlayAndEscapeClosesIt) {
  auto v = new_board();
  EXPECT_FALSE(v->help_shown());
  key(*v, SDLK_F1);
  EXPECT_TRUE(v->help_shown());
  key(*v, SDLK_F1);
  EXPECT_FALSE(v->help_shown());
  key(*v, SDLK_SLASH, KMOD_LSHIFT);  // '?'
  EXPECT_TRUE(v->help_shown());
  key(*v, SDLK_SLASH);  // '/' alone is not '?'
  EXPECT_TRUE(v->help_shown());
  key(*v, SDLK_ESCAPE);
  EXPECT_FALSE(v->help_shown());
  // Drawn, it is a panel: a click on it does not reach the board.
  key(*v, SDLK_F1);
  v->frame();  // an auto-sized window takes its size in its second frame
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  EXPECT_TRUE(v->over_panel(size.x / 2, size.y / 2));
}

}  // namespace
}  // namespace alloy::viewer

namespace alloy::viewer {
namespace {

TEST(ViewerCircuit, AMeterProbeOnThePaletteBatteryReadsVOverRWithinOnePercent) {
  auto v = palette_circuit();
  World& w = *v->world();
  for (int i = 0; i < 20; ++i) v->step_once();
  // A on the battery under the mouse puts a probe on it.
  v->push_mouse(SDL_MOUSEMOTION, test::position_of(w, "battery"));
  key(*v, SDLK_a);
  ASSERT_EQ(v->probes().size(), 1u) << all_messages(*v);
  const std::vector<std::string> r = v->probe_readings();
  ASSERT_EQ(r.size(), 1u);
  double amps = 0, volts = 0;
  ASSERT_EQ(std::sscanf(r[0].c_str(), "battery: %lf A, %lf V", &amps, &volts), 2) << r[0];
  // V / R over the loop: the emf over the battery's own resistance, the
  // switch, the lamp and the three wires, in series.
  double ohms = w.value<double>(w.find("battery"), "internal_resistance").value_or(0);
  for (const char* n : {"switch", "lamp", "wire", "wire_2", "wire_3"}) {
    ASSERT_TRUE(bool(w.find(n))) << n;
    ohms += w.value<double>(w.find(n), "resistance").value_or(0);
  }
  const double emf = w.value<double>(w.find("battery"), "emf").value_or(0);
  EXPECT_NEAR(amps, emf / ohms, 0.01 * emf / ohms) << r[0];
  // Its terminal voltage: the emf less what its own resistance takes.
  const double r_in = w.value<double>(w.find("battery"), "internal_resistance").value_or(0);
  EXPECT_NEAR(volts, emf - amps * r_in, 0.01 * emf) << r[0];
  // A again takes it off; a part with no current takes none.
  key(*v, SDLK_a);
  EXPECT_TRUE(v->probes().empty());
}

}  // namespace
}  // namespace alloy::viewer

namespace alloy::viewer {
namespace {

TEST(ViewerPlot, APlotKeepsTheLastSecondsOfAPropertyOneSampleAStepEqualToItsValues) {
  auto v = palette_circuit();
  v->set_paused(true);
  World& w = *v->world();
  const ObjectId lamp = w.find("lamp");
  EXPECT_FALSE(v->plot(lamp, "no_such_number"));
  EXPECT_FALSE(v->plot(lamp, "name"));  // not a number
  const double window = 0.05;
  const std::size_t n = std::size_t(std::lround(window / w.dt()));
  ASSERT_TRUE(v->plot(lamp, "current", window));
  std::vector<float> seen;
  for (int i = 0; i < int(n) + 15; ++i) {
    if (i == int(n) + 5) w.set(w.find("switch"), "switch_closed", false);  // the values change
    v->step_once();
    v->frame();
    seen.push_back(float(w.value<double>(lamp, "current").value_or(0)));
  }
  const std::vector<float>& got = v->plot_samples();
  ASSERT_EQ(got.size(), n);
  const std::vector<float> last(seen.end() - std::ptrdiff_t(n), seen.end());
  EXPECT_EQ(got, last);
  EXPECT_GT(std::abs(got.front()), 0.4f);  // the window holds the lit lamp and the dark one
  EXPECT_EQ(got.back(), 0.0f);
}

// --- recording (alloy view --record) ----------------------------------------------

/// A headless viewer of rigid_demo recording to `file`, running (not paused):
/// a bar dropped, moved by the hand and resized, a property set, then undone
/// and redone, with frames (steps) in between. run() ends it at `frames`
/// frames and writes the recording.
SaveData record_viewer_session(const std::string& file) {
  ViewerOptions o = test::headless(test::source("mods/rigid_demo"));
  o.record = file;
  o.frames = 30;
  Viewer v(o);
  EXPECT_TRUE(v.load_error().empty()) << v.load_error();
  v.frame();
  v.drop_part(entry("steel bar"), {0.0, 1.2});
  v.frame();
  World& w = *v.world();
  const ObjectId bar = w.find("steel_bar");
  EXPECT_TRUE(bool(bar));
  drag(v, test::position_of(w, "steel_bar"), {0.2, 1.4});
  v.select(bar);
  v.frame();
  if (const auto h = v.resize_handle()) drag(v, *h, *h + Vec2{0.05, 0});
  v.edit("set", [&] { return v.editor().set_property(bar, "friction", 0.9); });
  v.frame();
  key(v, SDLK_z, KMOD_LCTRL);
  v.frame();
  key(v, SDLK_y, KMOD_LCTRL);
  v.frame();
  std::ostringstream out, err;
  EXPECT_EQ(v.run(out, err), 0) << err.str();
  EXPECT_NE(out.str().find("recorded"), std::string::npos) << out.str();
  return read_save_file(file);
}

/// Builds the recording's scene afresh for replay().
struct Rebuild {
  std::string scene;
  std::optional<test::Loaded> loaded;
  World& operator()() {
    loaded.reset();
    loaded.emplace(test::load(scene));
    return loaded->world();
  }
};

// The viewer records through the world's input observer alone: drops, drags,
// resizes, the inspector, undo and redo are in the log without an edit site
// of their own, and the replay is identical through the last step. With a
// mass changed after the rigid body in one step, the report names that
// step, the stage and the property.
TEST(ViewerRecord, AnEditSessionReplaysIdentically) {
  const std::string file = (test::temp_dir() / "session.alloyrec").string();
  const SaveData rec = record_viewer_session(file);
  ASSERT_GT(rec.hashes.size(), 40u);
  std::set<ReplayInput::Kind> kinds;
  for (const auto& in : rec.inputs) kinds.insert(in.kind);
  for (const auto k : {ReplayInput::Kind::Create, ReplayInput::Kind::Set, ReplayInput::Kind::Sync,
                       ReplayInput::Kind::Restore})
    EXPECT_TRUE(kinds.contains(k)) << "the viewer's session logged no input of kind " << int(k);
  Rebuild rebuild{rec.meta.scene, {}};
  const ReplayResult r = replay(rec, std::ref(rebuild));
  EXPECT_TRUE(r.identical) << r.message();
  EXPECT_EQ(r.message(), "identical through step " + std::to_string(rec.hashes.back().step));

  const std::uint64_t at = rec.hashes[rec.hashes.size() / 2].step;
  ReplayOptions o;
  o.tamper = [&](World& w, std::uint64_t step, const std::string& stage) {
    if (step == at && stage == "rigid_body") w.set(w.find("ball"), "mass", 7.0);
  };
  const ReplayResult d = replay(rec, std::ref(rebuild), o);
  ASSERT_FALSE(d.identical);
  EXPECT_EQ(d.step, at) << d.message();
  EXPECT_EQ(d.stage, "rigid_body") << d.message();
  EXPECT_NE(std::find(d.properties.begin(), d.properties.end(), "mass"), d.properties.end())
      << d.message();
}

// A New board while recording: the recording follows the user. The part
// under way (rigid_demo) is written to FILE, and the new board is recorded
// from its own first snapshot to FILE-2.EXT, with the part dropped on it;
// each replays as identical. (Before, the recording stopped at the New.)
TEST(ViewerRecord, ANewBoardIsRecordedAsTheNextPart) {
  const fs::path dir = test::temp_dir();
  const fs::path first = dir / "board.alloyrec", second = dir / "board-2.alloyrec";
  fs::remove(first), fs::remove(second);
  ViewerOptions o = test::headless(test::source("mods/rigid_demo"));
  o.record = first.string();
  o.frames = 40;
  Viewer v(o);
  ASSERT_TRUE(v.load_error().empty()) << v.load_error();
  for (int i = 0; i < 10; ++i) v.frame();
  key(v, SDLK_n, KMOD_LCTRL);  // New (nothing edited: no question asked)
  ASSERT_NE(v.world()->find("floor"), ObjectId{}) << "no new board";
  v.frame();
  v.drop_part(entry("steel bar"), {0.0, 0.3});
  for (int i = 0; i < 5; ++i) v.frame();
  std::ostringstream out, err;
  EXPECT_EQ(v.run(out, err), 0) << err.str();
  ASSERT_TRUE(fs::exists(second)) << out.str();
  for (const fs::path& file : {first, second}) {
    const SaveData rec = read_save_file(file.string());
    ASSERT_GT(rec.hashes.size(), 5u) << file;
    Rebuild rebuild{rec.meta.scene, {}};
    const ReplayResult r = replay(rec, std::ref(rebuild));
    EXPECT_TRUE(r.identical) << file << ": " << r.message();
  }
  const SaveData board = read_save_file(second.string());
  EXPECT_EQ(board.meta.scene_name, "new board");
  EXPECT_TRUE(std::any_of(board.inputs.begin(), board.inputs.end(), [](const ReplayInput& in) {
    return in.kind == ReplayInput::Kind::Create;
  })) << "the part dropped on the new board was not recorded";
}

// Contact forces shown while recording: the viewer's demand for impulses is
// an input of the recording (World::demand_impulses), and the replay makes it
// again: identical. (Before, the replay, without the demand, parted at the
// first step the forces were shown.)
TEST(ViewerRecord, ContactForcesShownReplayIdentically) {
  const fs::path file = test::temp_dir() / "forces.alloyrec";
  ViewerOptions o = test::headless(test::source("mods/rigid_demo"));
  o.record = file.string();
  o.frames = 40;
  Viewer v(o);
  ASSERT_TRUE(v.load_error().empty()) << v.load_error();
  for (int i = 0; i < 5; ++i) v.frame();
  key(v, SDLK_g);  // magnetic forces (on by default) and contact forces off
  key(v, SDLK_g);  // both on
  ASSERT_TRUE(v.world()->impulses_demanded());
  std::ostringstream out, err;
  EXPECT_EQ(v.run(out, err), 0) << err.str();
  const SaveData rec = read_save_file(file.string());
  EXPECT_TRUE(std::any_of(rec.inputs.begin(), rec.inputs.end(), [](const ReplayInput& in) {
    return in.kind == ReplayInput::Kind::DemandImpulses;
  }));
  Rebuild rebuild{rec.meta.scene, {}};
  const ReplayResult r = replay(rec, std::ref(rebuild));
  EXPECT_TRUE(r.identical) << r.message();
}

}  // namespace
}  // namespace alloy::viewer

// --- a real editor's power (issue 17 item 7): many parts at once, copy and
// paste, snapping, the tooltip; and seeing the field (item 6) ------------------

namespace alloy::viewer {
namespace {

/// A press and release with Shift held (SDL reads the modifiers of a mouse
/// event from its keyboard state, which pushed events do not set).
void shift_drag(Viewer& v, Vec2 from, Vec2 to) {
  SDL_SetModState(KMOD_LSHIFT);
  drag(v, from, to);
  SDL_SetModState(KMOD_NONE);
}
void shift_click(Viewer& v, Vec2 at) {
  SDL_SetModState(KMOD_LSHIFT);
  click(v, at);
  SDL_SetModState(KMOD_NONE);
}

std::vector<ObjectId> of(World& w, std::initializer_list<const char*> names) {
  std::vector<ObjectId> out;
  for (const char* n : names) out.push_back(w.find(n));
  return out;
}

TEST(ViewerSelect, ShiftClickAndARubberBandSelectManyAndDeleteRemovesThemAllUndoably) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("steel bar"), {-0.2, 0.3});
  v->drop_part(entry("rubber ball"), {0, 0.3});
  v->drop_part(entry("steel disk"), {0.2, 0.3});
  click(*v, {-0.2, 0.3});
  shift_click(*v, {0, 0.3});
  EXPECT_EQ(v->selection(), of(w, {"steel_bar", "ball"}));
  shift_click(*v, {0, 0.3});  // again: taken away
  EXPECT_EQ(v->selection(), of(w, {"steel_bar"}));
  key(*v, SDLK_ESCAPE);
  click(*v, {0.5, 0.6});  // the board: nothing selected
  EXPECT_TRUE(v->selection().empty());
  // A band round the three (and over the floor, which is fixed: not taken).
  shift_drag(*v, {-0.35, 0.45}, {0.35, -0.05});
  EXPECT_EQ(v->selection(), of(w, {"steel_bar", "ball", "steel_disk"}));
  expect_undoable(*v, "remove three (Delete)", [&] { key(*v, SDLK_DELETE); });
  EXPECT_EQ(read_parts(w).size(), 1u) << "the floor alone is left";
}

TEST(ViewerSelect, DraggingOneOfManyCarriesThemAllByTheSameStepUndoably) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("steel bar"), {-0.2, 0.3});
  v->drop_part(entry("rubber ball"), {0.1, 0.3});
  shift_drag(*v, {-0.35, 0.45}, {0.35, 0.15});
  ASSERT_EQ(v->selection().size(), 2u);
  const Vec2 bar0 = test::position_of(w, "steel_bar"), ball0 = test::position_of(w, "ball");
  expect_undoable(*v, "move two", [&] { drag(*v, {0.1, 0.3}, {0.15, 0.4}); });
  const Vec2 bar1 = test::position_of(w, "steel_bar"), ball1 = test::position_of(w, "ball");
  EXPECT_NEAR(ball1.x - ball0.x, 0.05, 0.004);
  EXPECT_NEAR(ball1.y - ball0.y, 0.1, 0.004);
  EXPECT_NEAR(bar1.x - bar0.x, ball1.x - ball0.x, 1e-9);
  EXPECT_NEAR(bar1.y - bar0.y, ball1.y - ball0.y, 1e-9);
}

TEST(ViewerClipboard, CopyAndPasteOfACircuitBringsItsWiresAndItLightsLikeTheFirst) {
  auto v = palette_circuit();
  v->set_paused(true);
  World& w = *v->world();
  // Battery, switch and lamp in a band; the three wires among them come along.
  shift_drag(*v, {-0.1, 0.25}, {0.4, 0.0});
  std::vector<ObjectId> chosen = v->selection();
  std::sort(chosen.begin(), chosen.end());
  ASSERT_EQ(chosen, of(w, {"battery", "switch", "lamp"})) << all_messages(*v);
  Vec2 centre;
  for (const char* n : {"battery", "switch", "lamp"})
    centre = centre + test::position_of(w, n) * (1.0 / 3);
  key(*v, SDLK_c, KMOD_LCTRL);
  EXPECT_EQ(v->clipboard_parts(), 3u);
  EXPECT_NE(v->messages().back().find("3 parts and "), std::string::npos) << v->messages().back();
  v->push_mouse(SDL_MOUSEMOTION, {0.15, 0.45});
  expect_undoable(*v, "paste", [&] { key(*v, SDLK_v, KMOD_LCTRL); });
  const ObjectId lamp2 = w.find("lamp_2"), bat2 = w.find("battery_2");
  ASSERT_TRUE(lamp2 && bat2 && w.find("switch_2")) << all_messages(*v);
  // Moved as one: the copy's centre is where the mouse was (to a pixel).
  const Vec2 d = test::position_of(w, "lamp_2") - test::position_of(w, "lamp");
  const double px = 1 / v->camera().scale;
  EXPECT_NEAR(d.x, 0.15 - centre.x, px);
  EXPECT_NEAR(d.y, 0.45 - centre.y, px);
  EXPECT_NEAR(length(test::position_of(w, "battery_2") - test::position_of(w, "battery") - d), 0,
              1e-12);
  // The copied wires join the copies, not the first circuit.
  for (const char* n : {"wire_4", "wire_5", "wire_6"}) {
    const ObjectId wire = w.find(n);
    ASSERT_TRUE(bool(wire)) << n;
    for (const char* end : {"wire_from", "wire_to"}) {
      const ObjectId to = w.value<ObjectId>(wire, end).value_or(ObjectId{});
      const std::string name = w.describe(to);
      EXPECT_NE(name.find("_2"), std::string::npos) << n << "." << end << " -> " << name;
    }
  }
  // Run: the copy carries the current the first does.
  for (int i = 0; i < 20; ++i) v->step_once();
  v->frame();
  const double i1 = w.value<double>(w.find("lamp"), "current").value_or(0);
  const double i2 = w.value<double>(lamp2, "current").value_or(0);
  std::printf("lamp %.6f A, its pasted copy %.6f A\n", i1, i2);
  EXPECT_GT(std::abs(i1), 0.4);
  EXPECT_NEAR(i2, i1, 1e-9);
}

TEST(ViewerClipboard, APastedHingedBarKeepsItsHingeOnTheCopyAndAnEmptyPasteIsRefused) {
  auto v = new_board();
  World& w = *v->world();
  key(*v, SDLK_v, KMOD_LCTRL);
  EXPECT_NE(v->messages().back().find("nothing to paste"), std::string::npos);
  EXPECT_FALSE(v->history().can_undo());
  v->drop_part(entry("steel bar"), {0, 0.3});
  key(*v, SDLK_h);
  click(*v, {0.05, 0.3});  // the bar alone there: hinged to the board
  const ObjectId hinge = w.find("hinge");
  ASSERT_TRUE(bool(hinge)) << all_messages(*v);
  const Vec3 pivot = std::get<Vec3>(w.get(hinge, "anchor"));
  click(*v, {-0.03, 0.3});  // the bar alone is selected
  ASSERT_EQ(v->selection(), of(w, {"steel_bar"}));
  key(*v, SDLK_c, KMOD_LCTRL);
  v->push_mouse(SDL_MOUSEMOTION, {0.3, 0.5});
  key(*v, SDLK_v, KMOD_LCTRL);
  const ObjectId hinge2 = w.find("hinge_2");
  ASSERT_TRUE(bool(hinge2)) << all_messages(*v);
  EXPECT_EQ(w.value<ObjectId>(hinge2, "body_a").value_or(ObjectId{}), w.find("steel_bar_2"));
  EXPECT_FALSE(w.value<ObjectId>(hinge2, "body_b").value_or(ObjectId{}));
  // Its pivot moved with the bar: the same point of the copy.
  const Vec2 moved = test::position_of(w, "steel_bar_2") - test::position_of(w, "steel_bar");
  const Vec3 pivot2 = std::get<Vec3>(w.get(hinge2, "anchor"));
  EXPECT_NEAR(pivot2.x, pivot.x + moved.x, 1e-12);
  EXPECT_NEAR(pivot2.y, pivot.y + moved.y, 1e-12);
  EXPECT_GT(length(moved), 0.1);
  // The copy is selected; the original's hinge is untouched.
  EXPECT_EQ(v->selection(), of(w, {"steel_bar_2"}));
  EXPECT_EQ(w.value<ObjectId>(hinge, "body_a").value_or(ObjectId{}), w.find("steel_bar"));
  // Run: the copy swings about its own pivot.
  for (int i = 0; i < 60; ++i) v->step_once();
  v->frame();
  const Vec2 c2 = test::position_of(w, "steel_bar_2");
  EXPECT_NEAR(length(c2 - xy(pivot2)), 0.05, 1e-3) << "it hangs from its pivot";
}

TEST(ViewerSnap, AnEndSnapsOntoAnEndNearbyElseTheCentreOntoTheGrid) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("steel bar"), {0, 0.3});  // ends at x = -0.075 and 0.075
  v->drop_part(entry("brass bar"), {0.25, 0.5});
  key(*v, SDLK_x);
  ASSERT_TRUE(v->snapping());
  // The brass bar's left end let go 3 px from the steel bar's right end.
  const double px = 1 / v->camera().scale;
  const Vec2 off{3 * px, 2 * px};
  expect_undoable(*v, "snapped move", [&] {
    drag(*v, {0.25, 0.5}, Vec2{0.075 + 0.075, 0.3} + off);
  });
  EXPECT_NEAR(test::position_of(w, "brass_bar").x, 0.15, 1e-9);
  EXPECT_NEAR(test::position_of(w, "brass_bar").y, 0.3, 1e-9);
  // Far from every end: the centre on the 1 cm grid.
  drag(*v, {0.0, 0.3}, {-0.2537, 0.6041});
  const Vec2 c = test::position_of(w, "steel_bar");
  EXPECT_NEAR(c.x, -0.25, 1e-9);
  EXPECT_NEAR(c.y, 0.60, 1e-9);
  // Off: it stays where it is let go.
  key(*v, SDLK_x);
  drag(*v, {-0.25, 0.6}, {-0.2537, 0.6041});
  EXPECT_GT(std::abs(test::position_of(w, "steel_bar").x + 0.25), 1e-3);
}

TEST(ViewerTooltip, ThePartUnderTheMouseShowsItsNameMaterialSizeAndMass) {
  auto v = new_board();
  v->drop_part(entry("steel bar"), {0, 0.3});
  v->push_mouse(SDL_MOUSEMOTION, {0.02, 0.3});
  v->frame();
  const std::string t = v->tooltip();
  EXPECT_NE(t.find("steel_bar"), std::string::npos) << t;
  EXPECT_NE(t.find("steel"), std::string::npos) << t;
  EXPECT_NE(t.find("15.0 x 1.0 cm"), std::string::npos) << t;
  EXPECT_NE(t.find(" g"), std::string::npos) << t;
  v->push_mouse(SDL_MOUSEMOTION, {0.4, 0.6});  // the board: none
  v->frame();
  EXPECT_EQ(v->tooltip(), "");
}

TEST(ViewerCompass, NeedlesPointAwayFromNorthOnTheAxisAndBackAlongTheSide) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("magnet"), {0, 0.3});
  v->step_once();  // the poles are summed in a step
  v->frame();
  key(*v, SDLK_c);
  ASSERT_TRUE(v->compass());
  auto* forces = dynamic_cast<magnetism::MagneticForces*>(w.stage("magnetic_forces"));
  ASSERT_TRUE(forces);
  Vec2 north, south;
  for (const magnetism::Pole& p : forces->poles())
    (p.strength > 0 ? north : south) = xy(p.position);
  const Vec2 axis = (north - south) * (1 / length(north - south));
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  // As drawn, one every 36 px; here one every 6 px, to find one close to
  // each point asked about.
  ASSERT_GT(compass_needles(w, v->camera(), size.x, size.y).size(), 50u);
  const std::vector<Needle> needles = compass_needles(w, v->camera(), size.x, size.y, 6);
  auto nearest = [&](Vec2 p) {
    const Needle* best = &needles.front();
    for (const Needle& n : needles)
      if (length(n.at - p) < length(best->at - p)) best = &n;
    return *best;
  };
  // Beyond the north pole on the axis, B points on outwards; beyond the
  // south pole, in towards it; beside the magnet, from north to south.
  const Needle beyond_n = nearest(north + axis * 0.06), beyond_s = nearest(south - axis * 0.06);
  const Needle beside = nearest((north + south) * 0.5 + Vec2{-axis.y, axis.x} * 0.06);
  std::printf("needles: %zu; beyond N %.2f, beyond S %.2f, beside %.2f (cosines with the axis)\n",
              needles.size(), dot(beyond_n.north, axis), dot(beyond_s.north, axis),
              dot(beside.north, axis));
  EXPECT_GT(dot(beyond_n.north, axis), 0.9);
  EXPECT_GT(dot(beyond_s.north, axis), 0.9);
  EXPECT_LT(dot(beside.north, axis), -0.8);
  // Stronger near the magnet than far from it.
  EXPECT_GT(beyond_n.tesla, nearest(north + axis * 0.3).tesla);
}

}  // namespace
}  // namespace alloy::viewer
