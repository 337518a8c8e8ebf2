// The kit's newer tools in the viewer, headless: the spring with a damper
// (K), selecting and deleting one wire, the label layout, the script's `set`
// (the inspector's edit), and the doorbell built from an empty board by a
// script, saved, and rung by a fresh world loaded from the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <sstream>

#include "apps/viewer/input_script.hpp"
#include "apps/viewer/scene_draw.hpp"
#include "apps/viewer/viewer.hpp"
#include "runtime/error.hpp"
#include "runtime/state_hash.hpp"
#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

namespace fs = std::filesystem;

using test::click;
using test::entry;
using test::key;
using test::new_board;

/// Runs script lines (frames counted from now) to their end.
void run_script(Viewer& v, const std::string& lines) {
  v.add_script(parse_script(lines, "test.script"));
  for (int i = 0; i < 40; ++i) v.frame();
}
std::string last_message(Viewer& v) {
  return v.messages().empty() ? "" : v.messages().back();
}

std::vector<ObjectId> springs(World& w) {
  std::vector<ObjectId> out;
  if (const auto k = w.properties().find("spring_stiffness")) out = carriers(w.store(), *k);
  return out;
}

/// A rubber ball hung from a shelf by a spring made with the tool.
struct Hung {
  std::unique_ptr<Viewer> v;
  ObjectId ball, spring;
};
Hung hang_a_ball() {
  Hung h{new_board(), {}, {}};
  Viewer& v = *h.v;
  v.drop_part(entry("shelf"), {0, 0.45});
  v.drop_part(entry("rubber ball"), {0, 0.25});
  key(v, SDLK_k);
  click(v, {0, 0.45});  // the shelf ...
  click(v, {0, 0.25});  // ... to the ball's centre: 20 cm at rest
  World& w = *v.world();
  h.ball = w.find("ball");
  const auto s = springs(w);
  EXPECT_EQ(s.size(), 1u) << last_message(v);
  if (!s.empty()) h.spring = s.front();
  return h;
}

TEST(ViewerSpring, TheSpringToolHangsABallThatSettlesWhereMgOverKSays) {
  Hung h = hang_a_ball();
  ASSERT_TRUE(h.spring);
  Viewer& v = *h.v;
  World& w = *v.world();
  EXPECT_EQ(v.selected(), h.spring);
  // The rest length is the distance between the clicks, each on a whole pixel.
  const double rest = w.value<double>(h.spring, "spring_rest_length").value_or(0);
  EXPECT_NEAR(rest, 0.2, 0.003);
  EXPECT_EQ(w.value<double>(h.spring, "spring_stiffness"), Editor::kSpringStiffness);
  // Let go for 6 s: the damper (c / 2m = 0.68 /s on the 37 g ball) takes the
  // swing down to 2 % of its start; the ball rests m g / k below the rest length.
  const double m = w.value<double>(h.ball, "mass").value_or(0);
  for (int i = 0; i < int(std::lround(6 / w.dt())); ++i) v.step_once();
  v.frame();
  const auto ends = spring_ends(w, h.spring);
  ASSERT_TRUE(ends);
  const double stretch = length(ends->b - ends->a) - rest;
  const double sag = m * 9.81 / Editor::kSpringStiffness;
  std::printf("ball %.4f kg: the spring is %.5f m past its rest length, m g / k = %.5f m\n", m,
              stretch, sag);
  EXPECT_NEAR(stretch, sag, 2e-4);
  EXPECT_NEAR(ends->a.x, ends->b.x, 1e-3) << "it hangs straight down";
}

/// A scene with a ball hung from a shelf by kit.spring (its values from `spring`).
fs::path spring_scene(const std::string& spring) {
  const fs::path file = test::temp_dir() / "spring.lua";
  std::ofstream out(file);
  out << "local kit = require \"kit\"\n"
         "world { name = \"spring\", dt = 1 / 240 }\n"
         "kit.floor { name = \"shelf\", at = { 0, 0.5 }, size = { 0.3, 0.02 } }\n"
         "kit.disk { name = \"ball\", material = \"rubber\", at = { 0, 0.28 }, radius = 0.02 }\n"
      << spring << "\n";
  return file;
}

TEST(KitSpring, ALuaSceneHangsABallOnKitSpringAndAStiffOneIsRefusedByName) {
  test::Loaded l = test::load(
      spring_scene("kit.spring { name = \"hanger\", a = \"ball\", b = \"shelf\", at_b = { 0, -0.01 "
                   "}, stiffness = 20, rest_length = 0.2, damping = 0.05 }"));
  World& w = l.world();
  w.start();
  w.run(std::uint64_t(std::llround(6 / w.dt())));
  const ObjectId spring = w.find("hanger");
  const auto ends = spring_ends(w, spring);
  ASSERT_TRUE(ends);
  const double m = w.value<double>(w.find("ball"), "mass").value_or(0);
  const double stretch = length(ends->b - ends->a) - 0.2;
  std::printf("kit.spring: stretched %.5f m, m g / k = %.5f m\n", stretch, m * 9.81 / 20);
  EXPECT_NEAR(stretch, m * 9.81 / 20, 2e-4);
  try {
    test::load(
        spring_scene("kit.spring { name = \"stiff\", a = \"ball\", b = \"shelf\", "
                     "stiffness = 1e6, rest_length = 0.2 }"));
    FAIL() << "a spring too stiff for the step was loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'stiff'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("too stiff"), std::string::npos) << e.what();
  }
  try {
    test::load(
        spring_scene("kit.spring { name = \"loose\", a = \"ball\", stiffness = 20, "
                     "rest_length = 0.2 }"));
    FAIL() << "a spring with one end was loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("loose"), std::string::npos) << e.what();
  }
}

TEST(ViewerSpring, TheInspectorEditsItsStiffnessAndRefusesOneTooStiffByName) {
  Hung h = hang_a_ball();
  ASSERT_TRUE(h.spring);
  Viewer& v = *h.v;
  World& w = *v.world();
  run_script(v, "0 set spring_stiffness 40\n1 set spring_damping 0.2\n");
  EXPECT_EQ(w.value<double>(h.spring, "spring_stiffness"), 40.0) << last_message(v);
  EXPECT_EQ(w.value<double>(h.spring, "spring_damping"), 0.2);
  // 1e5 N/m on 37 g at 1/240 s: (h w)^2 = 47, refused, the value kept.
  run_script(v, "0 set spring_stiffness 100000\n");
  EXPECT_EQ(w.value<double>(h.spring, "spring_stiffness"), 40.0);
  const std::string m = last_message(v);
  EXPECT_NE(m.find("too stiff"), std::string::npos) << m;
  EXPECT_NE(m.find(w.describe(h.spring)), std::string::npos) << m;
  // Undo takes the stiffness back to the tool's.
  key(v, SDLK_z, KMOD_LCTRL);
  key(v, SDLK_z, KMOD_LCTRL);
  EXPECT_EQ(w.value<double>(h.spring, "spring_stiffness"), Editor::kSpringStiffness);
}

TEST(ViewerSpring, AClickOnItsLineSelectsItDeleteRemovesItAndRemovingItsPartTakesItAlong) {
  Hung h = hang_a_ball();
  ASSERT_TRUE(h.spring);
  Viewer& v = *h.v;
  key(v, SDLK_ESCAPE);
  click(v, {0.3, 0.1});  // empty board: nothing selected
  EXPECT_FALSE(v.selected());
  click(v, {0.001, 0.35});  // on the spring, between shelf and ball
  EXPECT_EQ(v.selected(), h.spring);
  key(v, SDLK_DELETE);
  World& w = *v.world();
  EXPECT_TRUE(springs(w).empty());
  EXPECT_TRUE(w.store().alive(h.ball));
  key(v, SDLK_z, KMOD_LCTRL);
  ASSERT_EQ(springs(*v.world()).size(), 1u);
  // Removing the ball takes its spring with it: no spring is left dangling.
  World& w2 = *v.world();
  const ObjectId ball = w2.find("ball");
  click(v, {0, 0.25});
  EXPECT_EQ(v.selected(), ball);
  key(v, SDLK_DELETE);
  EXPECT_TRUE(springs(*v.world()).empty()) << last_message(v);
}

TEST(ViewerWire, AClickOnAWireSelectsItAndDeleteRemovesThatWireAlone) {
  ViewerOptions o = test::headless("");
  auto v = std::make_unique<Viewer>(o);
  std::ifstream in(test::source("tests/viewer/scripts/circuit.script"));
  std::stringstream s;
  s << in.rdbuf();
  v->add_script(parse_script(s.str(), "circuit.script"));
  for (int i = 0; i < 34; ++i) v->frame();
  World& w = *v->world();
  const auto wire_prop = w.properties().find("wire_from");
  ASSERT_TRUE(wire_prop);
  const std::vector<ObjectId> wires = carriers(w.store(), *wire_prop);
  ASSERT_EQ(wires.size(), 3u);
  for (int i = 0; i < 60; ++i) v->step_once();
  v->frame();
  const ObjectId lamp = w.find("lamp");
  EXPECT_GT(std::abs(w.value<double>(lamp, "current").value_or(0)), 0.4);
  // The middle of the lamp-to-battery wire's curve (it sags below the parts).
  const ObjectId doomed = wires.back();
  const WireCurve c = *wire_curve(w, doomed);
  const Vec2 mid = c.a * 0.25 + c.control * 0.5 + c.b * 0.25;
  click(*v, mid);  // (over the floor: the wire is drawn on top)
  ASSERT_EQ(v->selected(), doomed) << last_message(*v);
  key(*v, SDLK_DELETE);
  EXPECT_FALSE(w.store().alive(doomed));
  EXPECT_EQ(carriers(w.store(), *wire_prop).size(), 2u);
  for (const char* part : {"battery", "switch", "lamp"}) EXPECT_TRUE(bool(w.find(part))) << part;
  for (int i = 0; i < 60; ++i) v->step_once();
  v->frame();
  EXPECT_LT(std::abs(w.value<double>(lamp, "current").value_or(1)), 1e-6) << "the loop is open";
}

TEST(ViewerLabels, NeighboursLabelsDoNotOverlapAndALoneLabelStaysAboveItsPart) {
  // The doorbell's pad (8 mm) lying on its rest (12 mm), 120 px to the cm:
  // both labels want the same place above them.
  const std::vector<LabelSpot> spots = {
      {100, 200, 110, 204, 22, 14}, {98, 204, 112, 216, 24, 14}, {400, 100, 460, 120, 40, 14}};
  const std::vector<LabelPlace> at = place_labels(spots);
  ASSERT_EQ(at.size(), 3u);
  auto overlaps = [&](std::size_t i, std::size_t j) {
    return at[i].x < at[j].x + spots[j].width && at[j].x < at[i].x + spots[i].width &&
           at[i].y < at[j].y + spots[j].height && at[j].y < at[i].y + spots[i].height;
  };
  for (std::size_t i = 0; i < at.size(); ++i)
    for (std::size_t j = i + 1; j < at.size(); ++j) EXPECT_FALSE(overlaps(i, j)) << i << " " << j;
  EXPECT_FALSE(at[0].moved);  // the first keeps its place above its part
  EXPECT_TRUE(at[1].moved);
  EXPECT_FALSE(at[2].moved);
  EXPECT_FLOAT_EQ(at[2].y, 100 - 3 - 14);
  EXPECT_FLOAT_EQ(at[2].x, 430 - 20);
}

TEST(ViewerScript, SetNamesItsLineWhenNothingIsSelectedOrTheValueIsBad) {
  EXPECT_THROW(parse_script("3 set spring_stiffness\n", "s.script"), InputError);
  auto v = new_board();
  run_script(*v, "0 set spring_stiffness 40\n");
  EXPECT_NE(last_message(*v).find("script line 1"), std::string::npos) << last_message(*v);
  EXPECT_NE(last_message(*v).find("nothing is selected"), std::string::npos);
  v->drop_part(entry("steel bar"), {0, 0.3});
  click(*v, {0, 0.3});
  run_script(*v, "0 set mass heavy\n");
  EXPECT_NE(last_message(*v).find("cannot read 'heavy'"), std::string::npos) << last_message(*v);
  run_script(*v, "0 set size 0.2 0.01 0.01\n1 set material brass\n");
  World& w = *v->world();
  const ObjectId bar = w.find("steel_bar");
  EXPECT_EQ(w.value<Vec3>(bar, "size"), (Vec3{0.2, 0.01, 0.01})) << last_message(*v);
  EXPECT_EQ(w.value<double>(bar, "density"), 8500.0) << last_message(*v);
}

/// A script of tests/viewer/scripts, then Save as `save_to`, run on a new
/// board until the file is written.
std::unique_ptr<Viewer> build_by_script(const std::string& script, const fs::path& save_to) {
  std::ifstream in(test::source("tests/viewer/scripts/" + script));
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_FALSE(s.str().empty()) << script << " not read";
  const std::vector<ScriptEvent> events = parse_script(s.str(), script);
  const int end = events.empty() ? 0 : events.back().frame;
  s << end + 2 << " key ctrl+shift+s\n"
    << end + 4 << " text " << save_to.string() << "\n"
    << end + 6 << " key Return\n";
  fs::remove(save_to);
  auto v = std::make_unique<Viewer>(test::headless(""));
  v->add_script(parse_script(s.str(), script));
  for (int i = 0; i < end + 10 && !fs::exists(save_to); ++i) v->frame();
  v->frame();
  for (const std::string& m : v->messages())
    EXPECT_EQ(m.find("script line"), std::string::npos) << m;  // every line did what it said
  return v;
}

/// The times of a world's `sound` events from `part` over `seconds`.
std::vector<double> strikes(World& w, const std::string& part, double seconds) {
  std::vector<double> t;
  w.add_observer([&](const Event& e) {
    if (e.type == "sound" && e.a && w.describe(e.a) == part) t.push_back(e.time);
  });
  w.run(std::uint64_t(std::llround(seconds / w.dt())));
  return t;
}

TEST(ViewerBuild, TheDoorbellBuiltByScriptOnAnEmptyBoardRingsSteadilyFromItsSavedFile) {
  const fs::path saved = test::temp_dir() / "doorbell.lua";
  auto v = build_by_script("doorbell.script", saved);
  ASSERT_TRUE(fs::exists(saved)) << (v->messages().empty() ? "" : v->messages().back());
  World& built = *v->world();
  EXPECT_EQ(built.time(), 0);
  // The file holds the board as it was built ...
  test::Loaded l = test::load(saved);
  World& w = l.world();
  w.start();
  EXPECT_EQ(hash_state(w).world, hash_state(built).world);
  // ... and rings: the bell is struck again and again, at a steady period.
  const std::vector<double> t = strikes(w, "bell", 3.0);
  ASSERT_GE(t.size(), 12u) << "the bell was struck " << t.size() << " times in 3 s";
  std::vector<double> gaps;
  for (std::size_t i = 2; i < t.size(); ++i) gaps.push_back(t[i] - t[i - 1]);
  double mean = 0;
  for (double g : gaps) mean += g / double(gaps.size());
  double spread = 0;
  for (double g : gaps) spread = std::max(spread, std::abs(g / mean - 1));
  std::printf(
      "doorbell built by script: %zu strikes in 3 s, first at %.3f s, period %.4f s "
      "(%.1f /s), spread %.1f %%\n",
      t.size(), t.front(), mean, 1 / mean, spread * 100);
  EXPECT_LT(spread, 0.25);
}

TEST(ViewerBuild, TheMotorBuiltByScriptOnAnEmptyBoardTurnsAnticlockwiseSteadilyFromItsSavedFile) {
  const fs::path saved = test::temp_dir() / "motor.lua";
  auto v = build_by_script("motor.script", saved);
  ASSERT_TRUE(fs::exists(saved)) << (v->messages().empty() ? "" : v->messages().back());
  World& built = *v->world();
  test::Loaded l = test::load(saved);
  World& w = l.world();
  w.start();
  EXPECT_EQ(hash_state(w).world, hash_state(built).world);
  // The hub is the palette's ball ("ball"): its mean angular velocity over
  // two halves of the run after the start-up, each about 4 turns of the rotor.
  const ObjectId hub = w.find("ball");
  ASSERT_TRUE(bool(hub));
  auto mean_spin = [&](double seconds) {
    const auto n = std::uint64_t(std::llround(seconds / w.dt()));
    double sum = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
      w.step();
      sum += std::get<Vec3>(w.get(hub, "angular_velocity")).z;
    }
    return sum / double(n);
  };
  mean_spin(1.5);  // the rod falls onto the spokes; the rotor starts
  const double first = mean_spin(1.75), second = mean_spin(1.75);
  std::printf(
      "motor built by script: %.3f rad/s (%.1f rpm) from 1.5 to 3.25 s, %.3f rad/s from "
      "3.25 to 5 s\n",
      first, first * 60 / (2 * std::numbers::pi), second);
  EXPECT_GT(first, 3.0) << "anticlockwise is +z";
  EXPECT_GT(second, 3.0);
  EXPECT_NEAR(second / first, 1.0, 0.1) << "steadily";
}

}  // namespace
}  // namespace alloy::viewer
