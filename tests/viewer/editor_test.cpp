// Tests for apps/viewer/editor: the player's edits on a world, without SDL.
#include "apps/viewer/editor.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "viewer_support.hpp"

namespace alloy::viewer {
namespace {

struct EditorTest : ::testing::Test {
  test::Loaded demo = test::load(test::source("mods/rigid_demo"));
  World& w = demo.world();
  Editor editor{&w};
  ObjectId id(const char* name) { return w.find(name); }
};

TEST_F(EditorTest, PickPrefersMovingPartsAndSmallOnes) {
  EXPECT_EQ(editor.pick({0.3, 1.5}), id("ball"));
  EXPECT_EQ(editor.pick({0, -0.05}), id("floor"));
  EXPECT_FALSE(editor.pick({0, 2.5}));
}

TEST_F(EditorTest, CarryAndDropMovesThePartAndTheWorldSeesIt) {
  ASSERT_TRUE(editor.grab(id("ball"), {0.3, 1.5}).ok);
  editor.carry_to({-0.5, 1.2});
  editor.hold();
  w.step();  // held: it stays where the hand is, whatever gravity says
  editor.hold();
  EXPECT_NEAR(test::position_of(w, "ball").x, -0.5, 1e-9);
  EXPECT_NEAR(test::position_of(w, "ball").y, 1.2, 1e-9);
  const EditResult r = editor.drop();
  EXPECT_TRUE(r.ok);
  EXPECT_TRUE(r.message.empty()) << r.message;
  w.run(24);  // let go: it falls
  EXPECT_LT(test::position_of(w, "ball").y, 1.2);
  EXPECT_NEAR(test::position_of(w, "ball").x, -0.5, 1e-6);
}

TEST_F(EditorTest, APartDroppedInsideAnotherIsMovedOut) {
  ASSERT_TRUE(editor.grab(id("ball"), {0.3, 1.5}).ok);
  editor.carry_to({0.3, -0.02});  // into the floor
  const EditResult r = editor.drop();
  EXPECT_TRUE(r.ok);
  EXPECT_NE(r.message.find("inside"), std::string::npos) << r.message;
  const auto ball = read_part(w, id("ball")), floor = read_part(w, id("floor"));
  EXPECT_LE(overlap_depth(*ball, *floor), Editor::kOverlapTolerance);
  EXPECT_GT(ball->centre.y, 0.05) << "moved up, out of the floor";
  w.run(240);  // and the world goes on calmly: the ball rests on the floor
  EXPECT_LT(std::abs(std::get<Vec3>(w.get(id("ball"), "velocity")).y), 3.0);
  EXPECT_GT(test::position_of(w, "ball").y, 0.05);
}

TEST_F(EditorTest, CarryingAPinnedWheelTakesItsPinAlong) {
  ASSERT_TRUE(editor.grab(id("wheel"), {2.4, 0.5}).ok);
  editor.carry_to({1.0, 1.0});
  editor.turn(std::numbers::pi / 2);
  editor.drop();
  const Vec3 anchor = std::get<Vec3>(w.get(id("axle"), "anchor"));
  EXPECT_NEAR(anchor.x, 1.0, 1e-9);
  EXPECT_NEAR(anchor.y, 1.0, 1e-9);
  w.run(120);
  EXPECT_NEAR(test::position_of(w, "wheel").x, 1.0, 0.01) << "the pin holds it where it was put";
  EXPECT_NEAR(test::position_of(w, "wheel").y, 1.0, 0.01);
}

TEST_F(EditorTest, PinAndUnpin) {
  EXPECT_TRUE(editor.set_pinned(id("plank"), true).ok);
  w.run(240);
  EXPECT_NEAR(test::position_of(w, "plank").y, 0.6, 1e-6) << "pinned: it stays in the air";
  EXPECT_TRUE(editor.toggle_pin(id("plank")).ok);
  EXPECT_FALSE(std::get<bool>(w.get(id("plank"), "pinned")));
  w.run(60);
  EXPECT_LT(test::position_of(w, "plank").y, 0.55) << "unpinned: it falls";
  EXPECT_FALSE(editor.set_pinned(id("floor"), true).ok) << "a static part is fixed already";
}

TEST_F(EditorTest, WiresGoFromConductorToConductorNeverToThemselves) {
  // Two conductive blocks and a battery, made property by property.
  auto block = [&](const char* name, double x, bool battery) {
    const ObjectId o = w.create(name);
    w.set(o, "shape", std::string("box"));
    w.set(o, "size", Vec3{0.1, 0.05, 0.05});
    w.set(o, "position", Vec3{x, 2.5, 0});
    w.set(o, "mass", 0.5);
    w.set(o, "pinned", true);
    w.set(o, "conductive", true);
    if (battery) w.set(o, "emf", 6.0);
    return o;
  };
  const ObjectId bat = block("bat", -1, true), a = block("a", 0, false);
  EditResult self = editor.connect_wire(a, {0, 2.5}, a, {0, 2.5});
  EXPECT_FALSE(self.ok);
  EXPECT_NE(self.message.find("itself"), std::string::npos);
  EXPECT_FALSE(editor.connect_wire(a, {0, 2.5}, id("plank"), {0.9, 0.6}).ok)
      << "wood does not conduct";
  const EditResult ok = editor.connect_wire(bat, {-0.96, 2.5}, a, {0, 2.5});
  ASSERT_TRUE(ok.ok) << ok.message;
  const ObjectId wire = w.find("wire");
  ASSERT_TRUE(bool(wire));
  EXPECT_EQ(std::get<ObjectId>(w.get(wire, "wire_from")), bat);
  EXPECT_EQ(std::get<std::int64_t>(w.get(wire, "wire_from_terminal")), 1) << "clicked at the + end";
  w.run(10);  // the world takes the wire
}

TEST_F(EditorTest, RemovingAPartTakesItsJointsAlong) {
  EXPECT_TRUE(editor.remove(id("wheel")).ok);
  EXPECT_FALSE(id("wheel"));
  EXPECT_FALSE(id("axle")) << "the pin went with the wheel";
  w.run(10);
  EXPECT_FALSE(editor.remove(ObjectId{}).ok);
}

TEST_F(EditorTest, UniqueNames) {
  EXPECT_EQ(editor.unique_name("ball"), "ball_2");
  EXPECT_EQ(editor.unique_name("anvil"), "anvil");
}

}  // namespace
}  // namespace alloy::viewer
