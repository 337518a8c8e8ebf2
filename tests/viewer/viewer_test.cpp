// Tests for apps/viewer/viewer: the whole viewer, headless (SDL's dummy video
// driver, software renderer), driven by synthesised SDL events exactly as a
// player's mouse drives it.
#include "apps/viewer/viewer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "apps/viewer/view_command.hpp"
#include "resolvers/magnetism/magnetic_forces.hpp"
#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

namespace fs = std::filesystem;

/// Share of the pixels in a (2r+1)^2 square about (x, y) within `tol` of `c`.
double share_of_colour(const Image& img, ScreenPoint at, ImU32 c, int r = 3, int tol = 10) {
  const int cr = int(c & 0xff), cg = int((c >> 8) & 0xff), cb = int((c >> 16) & 0xff);
  int hits = 0, n = 0;
  for (int y = int(at.y) - r; y <= int(at.y) + r; ++y)
    for (int x = int(at.x) - r; x <= int(at.x) + r; ++x) {
      if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
      const std::uint8_t* p = img.at(x, y);
      ++n;
      if (std::abs(p[0] - cr) <= tol && std::abs(p[1] - cg) <= tol && std::abs(p[2] - cb) <= tol)
        ++hits;
    }
  return n ? double(hits) / n : 0;
}

std::string describe_pixel(const Image& img, ScreenPoint at) {
  const std::uint8_t* p = img.at(int(at.x), int(at.y));
  std::ostringstream s;
  s << "pixel at (" << int(at.x) << ", " << int(at.y) << ") is rgb(" << int(p[0]) << ", "
    << int(p[1]) << ", " << int(p[2]) << ")";
  return s.str();
}

const fs::path kDemo = test::source("mods/rigid_demo");

TEST(Viewer, ScreenshotShowsTheFloorAndTheBallInTheirColours) {
  Viewer v(test::headless(kDemo));
  v.set_paused(true);
  v.frame();
  ASSERT_TRUE(v.load_error().empty()) << v.load_error();
  const Image img = v.render_image();
  ASSERT_EQ(img.width, 1280);
  ASSERT_EQ(img.height, 800);
  const ScreenPoint floor = v.camera().to_screen({0.8, -0.05});
  ASSERT_FALSE(v.over_panel(floor.x, floor.y));
  EXPECT_GT(share_of_colour(img, floor, colour::kStaticWood), 0.5) << describe_pixel(img, floor);
  const ScreenPoint ball = v.camera().to_screen({0.27, 1.52});
  EXPECT_GT(share_of_colour(img, ball, colour::kRubber, 2), 0.8) << describe_pixel(img, ball);
  const ScreenPoint pendulum = v.camera().to_screen({2.0, 1.8});
  EXPECT_GT(share_of_colour(img, pendulum, colour::kSteel, 1), 0.6)
      << describe_pixel(img, pendulum);
  const ScreenPoint wheel = v.camera().to_screen({2.4 - 0.07, 0.5 + 0.07});
  EXPECT_GT(share_of_colour(img, wheel, colour::kWood, 2), 0.8) << describe_pixel(img, wheel);
}

TEST(Viewer, TheCommandWritesAScreenshotAndSaysSo) {
  const fs::path png = test::temp_dir() / "demo.png";
  ViewerOptions o = test::headless(kDemo);
  o.screenshot = png.string();
  o.frames = 3;
  o.load = {};  // as the command line sets it
  std::ostringstream out, err;
  ASSERT_EQ(run_view(o, out, err), 0) << err.str();
  EXPECT_NE(out.str().find("screenshot"), std::string::npos);
  const Image img = read_png(png);
  EXPECT_EQ(img.width, 1280);
  EXPECT_EQ(img.height, 800);
  // The same options frame the scene the same way.
  Viewer v(test::headless(kDemo));
  v.frame();
  const ScreenPoint floor = v.camera().to_screen({0.8, -0.05});
  EXPECT_GT(share_of_colour(img, floor, colour::kStaticWood), 0.5) << describe_pixel(img, floor);
}

TEST(Viewer, AScriptedDragMovesThePartAndTheWorldSeesIt) {
  Viewer v(test::headless(kDemo));
  v.set_paused(true);
  v.frame();
  v.push_mouse(SDL_MOUSEMOTION, {0.3, 1.5});
  v.push_mouse(SDL_MOUSEBUTTONDOWN, {0.3, 1.5});
  v.frame();
  EXPECT_EQ(v.editor().carried(), v.world()->find("ball"));
  for (int i = 1; i <= 5; ++i) {
    v.push_mouse(SDL_MOUSEMOTION, {0.3 - 0.22 * i, 1.5 - 0.1 * i});
    v.frame();
  }
  v.push_mouse(SDL_MOUSEBUTTONUP, {-0.8, 1.0});
  v.frame();
  EXPECT_FALSE(v.editor().carrying());
  const double px = 1 / v.camera().scale;  // events are whole pixels
  const Vec2 ball = test::position_of(*v.world(), "ball");
  EXPECT_NEAR(ball.x, -0.8, 1.5 * px);
  EXPECT_NEAR(ball.y, 1.0, 1.5 * px);
  // Running, the world takes it from there: it falls from where it was put.
  v.set_paused(false);
  for (int i = 0; i < 10; ++i) v.frame();
  EXPECT_NEAR(test::position_of(*v.world(), "ball").x, -0.8, 1.5 * px);
  EXPECT_LT(test::position_of(*v.world(), "ball").y, 1.0 - 0.05);
}

TEST(Viewer, AScriptFileDrivesTheCommandAndTheSceneIsSaved) {
  const fs::path dir = test::temp_dir();
  std::ofstream(dir / "drag.txt") << "# carry the ball to the left, let go\n"
                                     "1 key space   # pause\n"
                                     "2 move 0.3 1.5\n"
                                     "3 press 0.3 1.5\n"
                                     "4 move -0.5 1.2\n"
                                     "5 move -1.0 1.1\n"
                                     "6 release -1.0 1.1\n";
  ViewerOptions o = test::headless(kDemo);
  o.script = (dir / "drag.txt").string();
  o.save = (dir / "dragged.lua").string();
  o.frames = 10;
  std::ostringstream out, err;
  ASSERT_EQ(run_view(o, out, err), 0) << err.str();
  auto saved = test::load(dir / "dragged.lua");
  EXPECT_NEAR(test::position_of(saved.world(), "ball").x, -1.0, 0.02);
  EXPECT_NEAR(test::position_of(saved.world(), "ball").y, 1.1, 0.02);
}

TEST(Viewer, ABadScriptLineIsNamed) {
  const fs::path dir = test::temp_dir();
  std::ofstream(dir / "bad.txt") << "1 move 0 0\n2 jump 1 1\n";
  ViewerOptions o = test::headless(kDemo);
  o.script = (dir / "bad.txt").string();
  std::ostringstream out, err;
  EXPECT_EQ(run_view(o, out, err), 2);
  EXPECT_NE(err.str().find("bad.txt:2"), std::string::npos) << err.str();
}

TEST(Viewer, APartDroppedInsideAnotherIsMovedOutAndNothingBreaks) {
  Viewer v(test::headless(kDemo));
  v.frame();
  v.push_mouse(SDL_MOUSEBUTTONDOWN, {0.3, 1.5});
  v.push_mouse(SDL_MOUSEMOTION, {0.5, 0.0});
  v.push_mouse(SDL_MOUSEBUTTONUP, {0.5, -0.05});  // into the floor
  v.frame();
  bool told = false;
  for (const auto& m : v.messages()) told |= m.find("inside") != std::string::npos;
  EXPECT_TRUE(told);
  for (int i = 0; i < 60; ++i) v.frame();
  const Vec2 ball = test::position_of(*v.world(), "ball");
  EXPECT_TRUE(std::isfinite(ball.x) && std::isfinite(ball.y));
  EXPECT_GT(ball.y, 0.0) << "on the floor, not in it";
}

// A quick hand, or xdotool under a real X server (xvfb_mouse_test.sh),
// clicks a palette button and then the board before the viewer draws its
// next frame: the move to the button, its press and release, the move to
// the board and the press and release there all come in one frame. Dear
// ImGui 1.86 reads the mouse once a frame, so the viewer hands the panels
// each of their button changes in a frame of its own
// (Viewer::waits_for_panels); the bar lands where the board was clicked.
TEST(Viewer, APaletteClickAndABoardClickInOneFrameStillPlaceThePart) {
  ViewerOptions o = test::headless({});  // a new board
  o.width = 1100;
  o.height = 700;
  Viewer v(o);
  v.set_paused(true);
  for (int i = 0; i < 3; ++i) v.frame();  // the panels laid out
  // The palette's "steel bar" at 1100 x 700 (docs/images/kit_new_board.png).
  const float bx = 68, by = 456;
  ASSERT_TRUE(v.over_panel(bx, by));
  const Vec2 button = v.camera().to_world(bx, by), board{0.3, 0.8};
  const ScreenPoint b = v.camera().to_screen(board);
  ASSERT_FALSE(v.over_panel(b.x, b.y));
  World& w = *v.world();
  ASSERT_FALSE(w.find("steel_bar"));
  v.push_mouse(SDL_MOUSEMOTION, button);
  v.push_mouse(SDL_MOUSEBUTTONDOWN, button);
  v.push_mouse(SDL_MOUSEBUTTONUP, button);
  v.push_mouse(SDL_MOUSEMOTION, board);
  v.push_mouse(SDL_MOUSEBUTTONDOWN, board);
  v.push_mouse(SDL_MOUSEBUTTONUP, board);
  for (int i = 0; i < 6; ++i) v.frame();
  ASSERT_TRUE(bool(w.find("steel_bar"))) << "the click on the palette was lost";
  const Vec2 at = test::position_of(w, "steel_bar");
  EXPECT_NEAR(at.x, board.x, 0.01);
  EXPECT_NEAR(at.y, board.y, 0.01);
}

TEST(Viewer, AWireToItselfIsRefusedAndAWireBetweenPartsIsMade) {
  Viewer v(test::headless(kDemo));
  v.set_paused(true);
  v.frame();
  World& w = *v.world();
  for (auto [name, x] : {std::pair{"block_a", -0.4}, std::pair{"block_b", 0.6}}) {
    const ObjectId o = w.create(name);
    w.set(o, "shape", std::string("box"));
    w.set(o, "size", Vec3{0.2, 0.1, 0.1});
    w.set(o, "position", Vec3{x, 1.0, 0});
    w.set(o, "mass", 0.5);
    w.set(o, "pinned", true);
    w.set(o, "conductive", true);
  }
  v.push_key(SDLK_w);
  v.push_mouse(SDL_MOUSEBUTTONDOWN, {-0.4, 1.0});
  v.push_mouse(SDL_MOUSEBUTTONUP, {-0.4, 1.0});
  v.push_mouse(SDL_MOUSEBUTTONDOWN, {-0.38, 1.01});
  v.push_mouse(SDL_MOUSEBUTTONUP, {-0.38, 1.01});
  v.frame();
  EXPECT_EQ(v.tool(), Tool::Wire);
  ASSERT_FALSE(v.messages().empty());
  EXPECT_NE(v.messages().back().find("itself"), std::string::npos) << v.messages().back();
  EXPECT_FALSE(w.find("wire"));
  v.push_mouse(SDL_MOUSEBUTTONDOWN, {-0.4, 1.0});
  v.push_mouse(SDL_MOUSEBUTTONUP, {-0.4, 1.0});
  v.push_mouse(SDL_MOUSEBUTTONDOWN, {0.6, 1.0});
  v.push_mouse(SDL_MOUSEBUTTONUP, {0.6, 1.0});
  v.frame();
  EXPECT_TRUE(bool(w.find("wire"))) << (v.messages().empty() ? "" : v.messages().back());
  v.set_paused(false);
  for (int i = 0; i < 5; ++i) v.frame();
}

TEST(Viewer, ASceneWithAnErrorIsShownWithFileAndLine) {
  const fs::path bad = test::source("tests/lua/bad_scenes/syntax_error.lua");
  Viewer v(test::headless(bad));
  for (int i = 0; i < 3; ++i) v.frame();
  EXPECT_EQ(v.world(), nullptr);
  EXPECT_NE(v.load_error().find("syntax_error.lua:"), std::string::npos) << v.load_error();
  const Image img = v.render_image();  // the error is drawn, nothing breaks
  EXPECT_TRUE(v.over_panel(640, 800.0f / 3)) << "the error panel is in the middle of the window";
  EXPECT_EQ(img.width, 1280);
  // The command exits 2 (bad input), and still writes its picture.
  ViewerOptions o = test::headless(bad);
  o.screenshot = (test::temp_dir() / "error.png").string();
  std::ostringstream out, err;
  EXPECT_EQ(run_view(o, out, err), 2);
  EXPECT_NE(err.str().find("syntax_error.lua:"), std::string::npos);
  EXPECT_TRUE(fs::exists(o.screenshot));
}

TEST(Viewer, FixingTheFileLoadsItAndABrokenResetKeepsTheWorld) {
  const fs::path file = test::temp_dir() / "scene.lua";
  std::ofstream(file)
      << "local kit = require \"kit\"\nkit.disk { name = \"d\", at = {0, 1}, radius = }\n";
  Viewer v(test::headless(file));
  v.frame();
  EXPECT_NE(v.load_error().find("scene.lua:2"), std::string::npos) << v.load_error();
  std::ofstream(file, std::ios::trunc)
      << "local kit = require \"kit\"\nkit.disk { name = \"d\", at = {0, 1}, radius = 0.1 }\n";
  fs::last_write_time(file, fs::last_write_time(file) + std::chrono::seconds(5));
  for (int i = 0; i < 40; ++i) v.frame();  // the file is looked at twice a second
  ASSERT_NE(v.world(), nullptr) << v.load_error();
  EXPECT_TRUE(v.load_error().empty());
  // Broken again: Reset keeps the running world and shows why.
  std::ofstream(file, std::ios::trunc) << "kit.nothing {}\n";
  v.reset();
  ASSERT_NE(v.world(), nullptr);
  EXPECT_FALSE(v.load_error().empty());
  EXPECT_TRUE(bool(v.world()->find("d")));
  for (int i = 0; i < 5; ++i) v.frame();
}

TEST(Viewer, EveryPaletteEntryTheKitCanMakeCanBeDropped) {
  Viewer v(test::headless(kDemo));
  v.set_paused(true);
  v.frame();
  PluginRegistry registry;
  register_native_plugins(registry);
  int made = 0;
  for (const PaletteEntry& e : palette_entries()) {
    if (!check_entry(registry, e, test::load_options()).empty()) continue;  // not in this kit
    const std::size_t before = v.world()->store().object_count();
    const EditResult r = v.drop_part(e, {-2.6 + 0.55 * (made % 10), 1.5 + 0.6 * (made / 10)});
    EXPECT_TRUE(r.ok) << e.label << ": " << r.message;
    EXPECT_GT(v.world()->store().object_count(), before) << e.label;
    ++made;
  }
  EXPECT_GE(made, 10);
  // Dropped into the floor, a shelf is moved out of it.
  const EditResult shelf = v.drop_part(palette_entries()[8], {1.0, 0.0});
  EXPECT_NE(shelf.message.find("inside"), std::string::npos) << shelf.message;
  v.set_paused(false);
  for (int i = 0; i < 60; ++i) v.frame();
  for (const Part2D& p : read_parts(*v.world()))
    EXPECT_TRUE(std::isfinite(p.centre.x) && std::isfinite(p.centre.y));
}

TEST(Viewer, PauseStepAndTimeScale) {
  Viewer v(test::headless(kDemo));
  v.set_paused(true);
  v.frame();
  EXPECT_EQ(v.world()->step_count(), 0u);
  v.push_key(SDLK_PERIOD);  // one step
  v.frame();
  EXPECT_EQ(v.world()->step_count(), 1u);
  v.push_key(SDLK_SPACE);  // run
  v.frame();
  EXPECT_EQ(v.world()->step_count(), 5u) << "1/60 s per frame at 1/240 s per step";
  v.set_time_scale(2);
  v.frame();
  EXPECT_EQ(v.world()->step_count(), 13u);
  v.push_key(SDLK_r, KMOD_CTRL);  // reset: the scene as the file says
  v.frame();
  EXPECT_LE(v.world()->step_count(), 8u);
}

TEST(Viewer, CtrlSSavesTheSceneWholeBesideItsFolder) {
  // A copy of the mod folder, opened from another working directory: Save
  // writes beside the folder, nothing into the working directory.
  const fs::path dir = test::temp_dir(), cwd = dir / "cwd";
  fs::create_directories(cwd);
  fs::copy(kDemo, dir / "rigid_demo",
           fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  const fs::path was = fs::current_path();
  fs::current_path(cwd);
  {
    Viewer v(test::headless(dir / "rigid_demo"));
    v.frame();
    v.push_key(SDLK_s, KMOD_CTRL);
    v.frame();
  }
  fs::current_path(was);
  EXPECT_TRUE(fs::is_empty(cwd));
  ASSERT_TRUE(fs::exists(dir / "rigid_demo_saved.lua"));
  auto saved = test::load(dir / "rigid_demo_saved.lua");
  EXPECT_TRUE(bool(saved.world().find("pendulum")));
}

TEST(Viewer, PinningByKeyHoldsThePartInTheAir) {
  Viewer v(test::headless(kDemo));
  v.frame();
  v.push_mouse(SDL_MOUSEMOTION, {0.9, 0.6});  // over the plank
  v.push_key(SDLK_p);
  v.frame();
  EXPECT_TRUE(std::get<bool>(v.world()->get(v.world()->find("plank"), "pinned")));
  const Vec2 before = test::position_of(*v.world(), "plank");
  for (int i = 0; i < 30; ++i) v.frame();
  EXPECT_NEAR(test::position_of(*v.world(), "plank").y, before.y, 1e-6);
}

}  // namespace
}  // namespace alloy::viewer

// --- the doorbell (mods/doorbell), once it is in the tree -------------------------

namespace alloy::viewer {
namespace {

const fs::path kDoorbell = test::source("mods/doorbell");

bool have_doorbell() {
  return fs::exists(kDoorbell / "mod.lua");
}

TEST(ViewerDoorbell, TheCoilsPolesAreRedAndGreenAndTheBellIsBronze) {
  if (!have_doorbell()) GTEST_SKIP() << "mods/doorbell is not here yet";
  Viewer v(test::headless(kDoorbell));
  v.frame();
  ASSERT_TRUE(v.load_error().empty()) << v.load_error();
  World& w = *v.world();
  const ObjectId coil = w.find("coil");
  ASSERT_TRUE(bool(coil));
  // Run until the coil is an electromagnet with poles.
  for (int i = 0; i < 600 && std::abs(std::get<double>(w.get(coil, "pole_strength"))) < 0.5; ++i)
    v.frame();
  v.set_paused(true);
  const double q = std::get<double>(w.get(coil, "pole_strength"));
  ASSERT_GT(std::abs(q), 0.5) << "the coil never came on";
  const Image img = v.render_image();
  auto* forces =
      dynamic_cast<magnetism::MagneticForces*>(w.stage(magnetism::MagneticForces::kName));
  ASSERT_NE(forces, nullptr);
  const magnetism::MagneticBody* body = forces->find(coil);
  ASSERT_NE(body, nullptr);
  ASSERT_EQ(body->pole_count, 2u);
  const magnetism::Pole north = forces->poles()[body->first_pole],
                        south = forces->poles()[body->first_pole + 1];
  EXPECT_GT(north.strength, 0);
  const ScreenPoint n = v.camera().to_screen(xy(north.position)),
                    s = v.camera().to_screen(xy(south.position));
  EXPECT_GT(share_of_colour(img, n, colour::kNorth, 1, 12), 0.5)
      << "north: " << describe_pixel(img, n);
  EXPECT_GT(share_of_colour(img, s, colour::kSouth, 1, 12), 0.5)
      << "south: " << describe_pixel(img, s);
  // The bell, a little off its centre (the radius line marks the centre).
  const auto bell = read_part(w, w.find("bell"));
  ASSERT_TRUE(bell);
  const ScreenPoint b =
      v.camera().to_screen(bell->centre + Vec2{-bell->radius * 0.4, bell->radius * 0.4});
  EXPECT_GT(share_of_colour(img, b, colour::kBronze, 2, 12), 0.5)
      << "bell: " << describe_pixel(img, b);
}

TEST(ViewerDoorbell, DroppingTheSwitchBarAcrossTheContactsRingsTheBell) {
  if (!have_doorbell()) GTEST_SKIP() << "mods/doorbell is not here yet";
  Viewer v(test::headless(kDoorbell));
  v.set_paused(true);
  v.frame();
  World& w = *v.world();
  const auto bar = read_part(w, w.find("switch_bar"));
  ASSERT_TRUE(bar);
  const Vec2 home = bar->centre;
  // Pick the bar up and hold it off to the side: the doorbell is open.
  v.push_mouse(SDL_MOUSEMOTION, home);
  v.push_mouse(SDL_MOUSEBUTTONDOWN, home);
  v.frame();
  ASSERT_EQ(v.editor().carried(), w.find("switch_bar"));
  const Vec2 aside = home + Vec2{-0.12, 0.06};
  v.push_mouse(SDL_MOUSEMOTION, aside);
  v.set_paused(false);
  for (int i = 0; i < 60; ++i)
    v.frame();  // a second: the scene's own timeline lets go of nothing held
  EXPECT_EQ(v.event_count("sound"), 0u) << "open: the bell is silent";
  EXPECT_EQ(v.event_count("circuit_closed"), 0u);
  // Across the two contacts, a centimetre above them, and let go.
  v.push_mouse(SDL_MOUSEMOTION, home + Vec2{0, 0.01});
  v.push_mouse(SDL_MOUSEBUTTONUP, home + Vec2{0, 0.01});
  v.frame();
  EXPECT_FALSE(v.editor().carrying());
  for (int i = 0; i < 120 && v.event_count("sound") == 0; ++i) v.frame();
  EXPECT_GT(v.event_count("circuit_closed"), 0u);
  EXPECT_GT(v.event_count("sound"), 0u) << "the bell rings";
  for (int i = 0; i < 30; ++i) v.frame();
  EXPECT_GT(v.audio().peak(), 0.0f) << "and it is heard: samples reached the audio output";
}

}  // namespace
}  // namespace alloy::viewer

namespace alloy::viewer {
namespace {

TEST(Viewer, AModThatErrsIsReportedAndTheWorldGoesOn) {
  const fs::path dir = test::temp_dir() / "jinx";
  fs::create_directories(dir);
  std::ofstream(dir / "mod.lua")
      << "return { name = \"jinx\", version = \"0.1.0\", depends = { \"kit\" },\n"
         "         runtime = \"runtime.lua\", scene = \"scene.lua\" }\n";
  std::ofstream(dir / "runtime.lua")
      << "mod.property { name = \"jinx\", doc = \"bad luck\" }\n"
         "mod.resolver { name = \"jinx.luck\", reads = { \"jinx\" }, writes = {}, needs = { "
         "\"jinx\" },\n"
         "  advance = function(w, dt) error(\"the jinx broke\") end }\n";
  std::ofstream(dir / "scene.lua")
      << "local kit = require \"kit\"\n"
         "world { settings = { [\"gravity.uniform\"] = { g = { 0, -9.81, 0 } } } }\n"
         "kit.floor { name = \"floor\", at = { 0, -0.05 }, size = { 2, 0.1 } }\n"
         "kit.disk { name = \"ball\", material = \"rubber\", at = { 0, 1 }, radius = 0.05, props = "
         "{ jinx = 1 } }\n";
  Viewer v(test::headless(dir));
  ASSERT_TRUE(v.load_error().empty()) << v.load_error();
  for (int i = 0; i < 30; ++i) v.frame();
  bool told = false;
  for (const auto& m : v.messages()) told |= m.find("jinx broke") != std::string::npos;
  EXPECT_TRUE(told) << "the mod's error is shown";
  EXPECT_FALSE(v.paused()) << "and the world goes on";
  EXPECT_GT(v.world()->time(), 0.4);
  EXPECT_LT(test::position_of(*v.world(), "ball").y, 0.9) << "the ball falls all the same";
}

}  // namespace
}  // namespace alloy::viewer
