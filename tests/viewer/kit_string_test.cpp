// The kit's string (issue 17 item 2), Save's file (no more `*_saved.lua` in
// the working directory) and the scripts' held modifiers:
// - a ball hung on a string from a pinned bar swings with the pendulum's
//   period 2 pi sqrt(L / g) (small angle) at two steps, on ODE and on Box2D
//   (the string is a spring that only pulls, rigid_body_from_springs, which
//   talks to the engine through its interface alone);
// - a slack string exerts nothing (a falling ball falls as if it were not
//   there, to the bit) and a taut one catches it;
// - in the viewer the T tool makes one string object, drawn, selectable,
//   removable, undoable, copied and pasted with its parts, saved by Save;
// - Save writes beside the opened scene, over a file the viewer wrote, never
//   over a scene written by hand; Save as asks before replacing a file; New
//   then Save asks for a path;
// - `keydown shift` / `keyup shift` in a script hold Shift through a press.
// Each physics test prints its figures (docs/kit.md, "Strings").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "apps/viewer/input_script.hpp"
#include "apps/viewer/viewer.hpp"
#include "runtime/state_hash.hpp"
#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
constexpr double kG = 9.81;

void write(const fs::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
}

std::string read(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A steel ball (a 2 cm disk) on a string of length `length` from the
/// centre of a pinned bar at (0, 1), let go at `angle` from the vertical;
/// `stretch` puts it that far beyond the string's length (its stretch under
/// the ball's weight, so that it does not bounce on the string).
std::string pendulum_scene(double dt, double length, double angle, double stretch) {
  const double r = length + stretch;
  char buf[1024];
  std::snprintf(buf, sizeof buf, R"(local kit = require "kit"
world { name = "pendulum", dt = %.17g, seconds = 10 }
kit.bar { name = "beam", material = "steel", at = { 0, 1 }, length = 0.2, width = 0.02, pinned = true }
kit.disk { name = "ball", material = "steel", at = { %.17g, %.17g }, radius = 0.02 }
kit.rope { name = "line", a = "ball", b = "beam", length = %.17g }
)",
                dt, r * std::sin(angle), 1 - r * std::cos(angle), length);
  return buf;
}

struct Swing {
  double period = 0;    ///< mean over the whole periods seen, s
  double expected = 0;  ///< 2 pi sqrt(L / g) (1 + angle^2 / 16), L the stretched length
  double mass = 0, stiffness = 0;
  int periods = 0;
};

Swing swing(double dt, const char* engine) {
  const fs::path dir = test::temp_dir();
  const double length = 0.5, angle = 0.05;
  // First the ball's mass and the string's stiffness (the kit's), for its stretch.
  const fs::path probe = dir / "probe.lua";
  write(probe, pendulum_scene(dt, length, angle, 0));
  Swing s;
  {
    auto l = test::load(probe);
    s.mass = l.world().value<double>(l.world().find("ball"), "mass").value_or(0);
    s.stiffness = l.world().value<double>(l.world().find("line"), "spring_stiffness").value_or(0);
  }
  const double stretch = s.mass * kG * std::cos(angle) / s.stiffness;
  const fs::path file = dir / "pendulum.lua";
  write(file, pendulum_scene(dt, length, angle, stretch));
  auto l = test::load(file);
  World& w = l.world();
  if (engine) w.swap("", "rigid_body", engine);
  const ObjectId ball = w.find("ball");
  std::vector<double> crossings;  // the ball going left to right through x = 0
  double x0 = std::get<Vec3>(w.get(ball, "position")).x;
  const auto steps = std::llround(8.0 / dt);
  for (long long i = 0; i < steps; ++i) {
    w.step();
    const double x1 = std::get<Vec3>(w.get(ball, "position")).x;
    if (x0 < 0 && x1 >= 0) crossings.push_back(dt * (double(i) + x0 / (x0 - x1)));
    x0 = x1;
  }
  if (crossings.size() >= 2) {
    s.periods = int(crossings.size()) - 1;
    s.period = (crossings.back() - crossings.front()) / s.periods;
  }
  const double L = length + stretch;
  s.expected = 2 * kPi * std::sqrt(L / kG) * (1 + angle * angle / 16);
  return s;
}

TEST(KitString, ABallOnAStringSwingsWithThePendulumsPeriodOnBothEnginesAtTwoSteps) {
  for (const char* engine : {static_cast<const char*>(nullptr), "rigid_body.box2d"}) {
    for (const double dt : {1.0 / 240, 1.0 / 960}) {
      const Swing s = swing(dt, engine);
      const double error = s.period / s.expected - 1;
      std::printf(
          "string pendulum on %s at 1/%.0f s: m %.4g kg, k %.4g N/m, %d periods of %.6f s "
          "(2 pi sqrt(L/g) (1 + a^2/16) = %.6f s): %+.4f %%\n",
          engine ? engine : "rigid_body (ODE)", 1 / dt, s.mass, s.stiffness, s.periods, s.period,
          s.expected, 100 * error);
      EXPECT_GE(s.periods, 4) << (engine ? engine : "ODE") << " at " << dt;
      EXPECT_NEAR(error, 0, 2e-3) << (engine ? engine : "ODE") << " at " << dt;
    }
  }
}

/// A ball let fall under a pinned bar, with or without a string of
/// `length` from the bar's centre to it; its height after each step.
std::vector<double> fall(const char* engine, double length) {
  const fs::path file = test::temp_dir() / "fall.lua";
  std::string scene = R"(local kit = require "kit"
world { name = "fall", dt = 1 / 240, seconds = 1 }
kit.bar { name = "beam", material = "steel", at = { 0, 1 }, length = 0.2, width = 0.02, pinned = true }
kit.disk { name = "ball", material = "steel", at = { 0, 0.8 }, radius = 0.02 }
)";
  if (length > 0)
    scene += "kit.rope { name = \"line\", a = \"ball\", b = \"beam\", length = " +
             std::to_string(length) + " }\n";
  write(file, scene);
  auto l = test::load(file);
  World& w = l.world();
  if (engine) w.swap("", "rigid_body", engine);
  const ObjectId ball = w.find("ball");
  std::vector<double> y;
  for (int i = 0; i < 240; ++i) {
    w.step();
    y.push_back(std::get<Vec3>(w.get(ball, "position")).y);
  }
  return y;
}

TEST(KitString, ASlackStringExertsNothingAndATautOneCatchesTheBall) {
  for (const char* engine : {static_cast<const char*>(nullptr), "rigid_body.box2d"}) {
    SCOPED_TRACE(engine ? engine : "ODE");
    const std::vector<double> free = fall(engine, 0), slack = fall(engine, 0.5);
    // 0.3 m of string to spare: slack for the first sqrt(2 * 0.3 / g) = 0.247 s.
    for (std::size_t i = 0; i < 55; ++i) ASSERT_EQ(free[i], slack[i]) << "step " << i + 1;
    // Then it is taut and catches the ball 0.5 m under the bar: it stretches
    // as the ball's fall of 0.3 m asks, m g (0.3 + x) = k x^2 / 2 (x = 8.6 cm
    // for 0.263 kg on 300 N/m), and throws it back up; the free ball falls on.
    const double lowest = *std::min_element(slack.begin(), slack.end());
    EXPECT_LT(free.back(), 0.0);
    EXPECT_GT(lowest, 1 - 0.5 - 0.1);
    EXPECT_LT(lowest, 1 - 0.5);
    std::printf(
        "%s: after 1 s the free ball is at y = %.4f m; the one on the string fell to "
        "%.4f m at the lowest\n",
        engine ? engine : "ODE", free.back(), lowest);
  }
}

// --- in the viewer -------------------------------------------------------------------

using test::click;
using test::entry;
using test::key;
using test::new_board;

std::string messages(Viewer& v) {
  std::string s;
  for (const auto& m : v.messages()) s += m + "\n";
  return s;
}

std::uint64_t hash(Viewer& v) {
  return hash_state(*v.world()).world;
}

TEST(KitString, TheStringToolMakesOneStringThatIsSelectedDeletedUndoneCopiedAndSaved) {
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("shelf"), {0, 0.4});
  v->drop_part(entry("rubber ball"), {0.0, 0.2});
  v->frame();  // the world made whole after the edit, as a redo leaves it
  const std::uint64_t before = hash(*v);
  key(*v, SDLK_t);
  click(*v, {0.0, 0.39});
  click(*v, {0.0, 0.21});
  const ObjectId st = w.find("string");
  ASSERT_TRUE(bool(st)) << messages(*v);
  EXPECT_EQ(w.value<bool>(st, "spring_slack"), true);
  EXPECT_NEAR(w.value<double>(st, "spring_rest_length").value_or(0), 0.18, 0.004);
  EXPECT_EQ(v->selected(), st);  // made, it is selected
  const std::uint64_t made = hash(*v);
  // Undone and redone to the same hash.
  key(*v, SDLK_z, KMOD_LCTRL);
  EXPECT_EQ(hash(*v), before);
  EXPECT_FALSE(bool(w.find("string")));
  key(*v, SDLK_y, KMOD_LCTRL);
  EXPECT_EQ(hash(*v), made);
  // A click on its middle selects it; Delete removes it alone, undoably.
  key(*v, SDLK_ESCAPE);
  click(*v, {0.0, 0.3});
  ASSERT_EQ(v->selected(), w.find("string")) << messages(*v);
  key(*v, SDLK_DELETE);
  EXPECT_FALSE(bool(w.find("string")));
  EXPECT_TRUE(bool(w.find("ball")) && bool(w.find("shelf")));
  key(*v, SDLK_z, KMOD_LCTRL);
  ASSERT_TRUE(bool(w.find("string")));
  EXPECT_EQ(hash(*v), made);
  // Copied with its parts (both selected), it comes along, tied to the copies.
  click(*v, {0.0, 0.2});
  SDL_SetModState(KMOD_LSHIFT);
  click(*v, {0.1, 0.4});
  SDL_SetModState(KMOD_NONE);
  ASSERT_EQ(v->selection().size(), 2u) << messages(*v);
  key(*v, SDLK_c, KMOD_LCTRL);
  v->push_mouse(SDL_MOUSEMOTION, {0.3, 0.3});
  key(*v, SDLK_v, KMOD_LCTRL);
  const ObjectId copy = w.find("string_2");
  ASSERT_TRUE(bool(copy)) << messages(*v);
  EXPECT_EQ(w.value<bool>(copy, "spring_slack"), true);
  EXPECT_EQ(w.value<ObjectId>(copy, "spring_a"), w.find("shelf_2"));  // clicked first
  EXPECT_EQ(w.value<ObjectId>(copy, "spring_b"), w.find("ball_2"));
  // Saved and loaded again: a string still, with the same values.
  const fs::path file = test::temp_dir() / "strings.lua";
  fs::remove(file);
  key(*v, SDLK_s, KMOD_LCTRL | KMOD_LSHIFT);
  v->add_script(parse_script("1 text " + file.string() + "\n3 key Return\n", "t"));
  for (int i = 0; i < 5; ++i) v->frame();
  ASSERT_TRUE(fs::exists(file)) << messages(*v);
  auto saved = test::load(file);
  EXPECT_EQ(saved.world().value<bool>(saved.world().find("string_2"), "spring_slack"), true);
  std::string differ;
  for (const std::string& d : hash_differences(hash_state(saved.world()), hash_state(w)))
    differ += d + "; ";
  // The same objects with the same property values (the board's world has
  // its stages' states too, which a loaded file makes at its first step).
  EXPECT_EQ(hash_state(saved.world()).objects, hash_state(w).objects) << differ;
  EXPECT_EQ(hash_state(saved.world()).columns, hash_state(w).columns) << differ;
  // Running, the ball hangs on it (without, it would lie on the floor at 0.02).
  v->set_paused(false);
  for (int i = 0; i < 60; ++i) v->frame();
  EXPECT_GT(test::position_of(w, "ball").y, 0.15);
  EXPECT_GT(test::position_of(w, "ball_2").y, 0.15);
}

// --- Save's file ------------------------------------------------------------------------

TEST(ViewerSave, SaveWritesBesideAHandWrittenSceneAndOverItsOwnNeverInTheWorkingDirectory) {
  const fs::path dir = test::temp_dir(), scenes = dir / "scenes", cwd = dir / "cwd";
  fs::create_directories(scenes);
  fs::create_directories(cwd);
  const fs::path hand = scenes / "board.lua";
  const std::string text =
      "-- a board written by hand\nlocal kit = require \"kit\"\nworld { name = \"board\" }\n"
      "kit.floor { name = \"floor\", at = { 0, -0.01 }, size = { 1.0, 0.02 } }\n";
  write(hand, text);
  const fs::path was = fs::current_path();
  fs::current_path(cwd);
  {
    ViewerOptions o = test::headless(hand);
    o.paused = true;
    Viewer v(o);
    v.frame();
    EXPECT_EQ(v.save_path(), (scenes / "board_saved.lua").string());
    v.drop_part(entry("steel bar"), {0, 0.3});
    key(v, SDLK_s, KMOD_LCTRL);
    EXPECT_FALSE(v.asking_for_path());
    EXPECT_TRUE(fs::exists(scenes / "board_saved.lua")) << messages(v);
    EXPECT_EQ(read(hand), text) << "a scene written by hand is never overwritten by Save";
    // The saved file, opened, is saved over (it is the viewer's own).
    ASSERT_TRUE(v.open(scenes / "board_saved.lua")) << messages(v);
    EXPECT_EQ(v.save_path(), (scenes / "board_saved.lua").string());
    v.drop_part(entry("rubber ball"), {0.2, 0.3});
    key(v, SDLK_s, KMOD_LCTRL);
    auto again = test::load(scenes / "board_saved.lua");
    EXPECT_TRUE(bool(again.world().find("ball")) && bool(again.world().find("steel_bar")));
    // A mod folder is saved beside the folder.
    ASSERT_TRUE(v.open(test::source("mods/rigid_demo")));
    EXPECT_EQ(v.save_path(), test::source("mods/rigid_demo_saved.lua").string());
  }
  fs::current_path(was);
  EXPECT_TRUE(fs::is_empty(cwd)) << "Save wrote into the working directory";
  EXPECT_EQ(Viewer::save_path_for("mods/doorbell/"), fs::path("mods/doorbell_saved.lua"));
  EXPECT_EQ(Viewer::save_path_for("x.lua"), fs::path("x_saved.lua"));
}

TEST(ViewerSave, SaveAsAsksBeforeReplacingAnotherFileAndNewThenSaveAsksForAPath) {
  auto v = new_board();
  v->drop_part(entry("rubber ball"), {0, 0.3});
  // New, then Ctrl+S: a path is asked for, nothing is written.
  key(*v, SDLK_s, KMOD_LCTRL);
  EXPECT_TRUE(v->asking_for_path());
  key(*v, SDLK_ESCAPE);
  EXPECT_FALSE(v->asking_for_path());
  const fs::path other = test::temp_dir() / "other.lua";
  write(other, "world { name = \"mine\" }\n");
  // Save as onto a file that is there: asked; Esc leaves it as it was.
  key(*v, SDLK_s, KMOD_LCTRL | KMOD_LSHIFT);
  v->add_script(parse_script("1 text " + other.string() + "\n3 key Return\n", "t"));
  for (int i = 0; i < 5; ++i) v->frame();
  EXPECT_EQ(v->asking_to_overwrite(), other.string()) << messages(*v);
  key(*v, SDLK_ESCAPE);
  EXPECT_EQ(read(other), "world { name = \"mine\" }\n");
  EXPECT_TRUE(v->untitled());
  // Again, and Enter: replaced; the board is that file from now on.
  key(*v, SDLK_s, KMOD_LCTRL | KMOD_LSHIFT);
  v->add_script(parse_script("1 text " + other.string() + "\n3 key Return\n5 key Return\n", "t"));
  for (int i = 0; i < 7; ++i) v->frame();
  EXPECT_TRUE(Viewer::written_by_viewer(other)) << messages(*v);
  EXPECT_EQ(v->save_path(), other.string());
  EXPECT_FALSE(v->untitled());
  // Its own file is saved over without a question.
  v->drop_part(entry("steel bar"), {0.2, 0.3});
  key(*v, SDLK_s, KMOD_LCTRL);
  EXPECT_TRUE(v->asking_to_overwrite().empty());
  auto saved = test::load(other);
  EXPECT_TRUE(bool(saved.world().find("steel_bar")));
}

// --- drawing a part to size -------------------------------------------------------------

TEST(ViewerDraw, ABarIsDrawnFromPressToReleaseAndADiskToItsRadiusInOneUndoableEdit) {
  auto v = new_board();
  World& w = *v->world();
  v->frame();
  const std::uint64_t empty = hash(*v);
  // A bar from (-0.1, 0.3) to (0.1, 0.4): 22.4 cm long, at 26.6 degrees.
  v->add_script(parse_script(R"(1 palette steel bar
2 move -0.1 0.3
3 press -0.1 0.3
4 move 0 0.35
5 move 0.1 0.4
6 release 0.1 0.4
)",
                             "draw"));
  for (int i = 0; i < 8; ++i) v->frame();
  const ObjectId bar = w.find("steel_bar");
  ASSERT_TRUE(bool(bar)) << messages(*v);
  const auto p = read_part(w, bar);
  ASSERT_TRUE(p.has_value());
  const double px = 1 / v->camera().scale;  // a click lands on a whole pixel
  EXPECT_NEAR(2 * p->half.x, std::hypot(0.2, 0.1), 3 * px);
  EXPECT_NEAR(2 * p->half.y, 0.01, 1e-9);  // the palette's thickness
  EXPECT_NEAR(p->angle, std::atan2(0.1, 0.2), 0.03);
  EXPECT_NEAR(p->centre.x, 0, 2 * px);
  EXPECT_NEAR(p->centre.y, 0.35, 2 * px);
  // Its mass follows its volume (steel: 7850 kg/m^3, 1 cm square).
  EXPECT_NEAR(w.value<double>(bar, "mass").value_or(0), 7850 * 2 * p->half.x * 0.01 * 0.01, 1e-9);
  EXPECT_EQ(v->history().undo_depth(), 1u) << "the drop and its drawing are one edit";
  const std::uint64_t drawn = hash(*v);
  key(*v, SDLK_z, KMOD_LCTRL);
  EXPECT_EQ(hash(*v), empty);
  key(*v, SDLK_y, KMOD_LCTRL);
  EXPECT_EQ(hash(*v), drawn);
  // A disk dragged 6 cm from its centre; a click alone keeps the palette's size.
  v->add_script(parse_script(R"(1 palette steel disk
2 move 0.3 0.3
3 press 0.3 0.3
4 move 0.36 0.3
5 release 0.36 0.3
7 palette steel bar
8 move -0.3 0.5
9 press -0.3 0.5
10 release -0.3 0.5
)",
                             "disk"));
  for (int i = 0; i < 12; ++i) v->frame();
  const auto disk = read_part(w, w.find("steel_disk"));
  ASSERT_TRUE(disk.has_value()) << messages(*v);
  EXPECT_NEAR(disk->radius, 0.06, 2 * px);
  const auto clicked = read_part(w, w.find("steel_bar_2"));
  ASSERT_TRUE(clicked.has_value()) << messages(*v);
  EXPECT_NEAR(2 * clicked->half.x, 0.15, 1e-9);
}

// --- held modifiers in scripts ------------------------------------------------------------

TEST(ViewerScript, KeydownShiftHoldsShiftThroughAPressSoARubberBandSelects) {
  EXPECT_THROW(parse_script("1 keydown q\n", "s"), InputError);
  EXPECT_THROW(parse_script("1 keyup\n", "s"), InputError);
  auto v = new_board();
  World& w = *v->world();
  v->drop_part(entry("steel bar"), {0, 0.3});
  v->drop_part(entry("rubber ball"), {0.2, 0.3});
  v->drop_part(entry("steel disk"), {0.4, 0.3});
  v->select({});
  // A band over the bar and the ball (not the disk), Shift held by the script.
  v->add_script(parse_script(R"(1 keydown shift
2 move -0.1 0.4
3 press -0.1 0.4
4 move 0.1 0.3
5 move 0.25 0.2
6 release 0.25 0.2
8 keyup shift
)",
                             "band"));
  for (int i = 0; i < 10; ++i) v->frame();
  std::vector<ObjectId> chosen = v->selection();
  std::sort(chosen.begin(), chosen.end());
  std::vector<ObjectId> want{w.find("steel_bar"), w.find("ball")};
  std::sort(want.begin(), want.end());
  EXPECT_EQ(chosen, want) << messages(*v);
  EXPECT_EQ(SDL_GetModState() & KMOD_SHIFT, 0) << "keyup let it go";
}

}  // namespace
}  // namespace alloy::viewer
