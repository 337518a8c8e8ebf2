// Tests for resolvers/sound/sound_from_collisions.hpp through the real rigid
// body and collisions set (paper 4.1.6: the striker hits the bell, "ding"):
// a ball dropped on a bell makes it ring at its pitch, two steps after the
// touch; a harder fall rings louder; a part set down gently stays silent; both
// parts of a pair ring if both can; a bouncing ball rings at every bounce.
#include "resolvers/sound/sound_from_collisions.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "resolvers/plugins.hpp"
#include "resolvers/sound/sound_plugins.hpp"
#include "tests/resolvers/sound/goertzel.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace alloy::sound {
namespace {

using test::goertzel;
using test::rms;
using test::window;

constexpr double kBellPitch = 1000;
constexpr double kBallRadius = 0.02;
constexpr double kBellTop = 0.025;  // the bell is a 0.2 x 0.05 x 0.05 box at the origin

class SoundFromCollisionsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    register_native_plugins(registry);
    register_sound_plugins(registry);  // replaces itself if the native set has it
  }

  /// A pinned 2 kg bell (it keeps its mass) and a 0.1 kg ball `drop` m above it.
  void build(World& w, double drop, double restitution = 0) {
    bell = scenes::add_box(w, {0, 0, 0}, {0.2, 0.05, 0.05}, 2.0, {}, "bell");
    w.set(bell, "pinned", true);
    w.set(bell, "acoustic", std::string("bell"));
    w.set(bell, "pitch", kBellPitch);
    w.set(bell, "decay", 2.0);
    ball = scenes::add_sphere(w, {0, kBellTop + kBallRadius + drop, 0}, kBallRadius, 0.1, "ball");
    if (restitution > 0) w.set(ball, "restitution", restitution);
  }
  static SoundResolver& sound(World& w) { return dynamic_cast<SoundResolver&>(*w.stage("sound")); }

  /// Steps until `seconds` have passed, recording contact_began and sound events.
  void run(World& w, double seconds) {
    const auto n = std::uint64_t(std::llround(seconds / w.dt()));
    for (std::uint64_t k = 0; k < n; ++k) {
      w.step();
      for (const Event& e : w.events()) {
        if (e.type == "contact_began" && began_step == 0) began_step = w.step_count();
        if (e.type == "sound") sounds.push_back(e), sound_steps.push_back(w.step_count());
      }
    }
  }

  PluginRegistry registry;
  ObjectId bell, ball;
  std::uint64_t began_step = 0;
  std::vector<Event> sounds;
  std::vector<std::uint64_t> sound_steps;
};

TEST_F(SoundFromCollisionsTest, ABallDroppedOnABellMakesItRingAtItsPitch) {
  World w(registry);
  build(w, 0.1);
  run(w, 0.6);
  ASSERT_GT(began_step, 0u) << "the ball never reached the bell";
  ASSERT_EQ(sounds.size(), 1u);
  const Event& ding = sounds[0];
  EXPECT_EQ(ding.a, bell);
  EXPECT_EQ(ding.b, ball);
  EXPECT_EQ(ding.source, "sound");
  EXPECT_DOUBLE_EQ(ding.value("pitch"), kBellPitch);
  // Touch at derive of step n; the rigid body resolves it in n + 1, the
  // interaction strikes with its impulse, the sound resolver rings in n + 2.
  EXPECT_EQ(sound_steps[0], began_step + 2);
  // The blow as the bell felt it: the ball's impulse over the bell's mass.
  // Falling 0.1 m the ball arrives at sqrt(2 g h) = 1.40 m/s and stops
  // (restitution 0): J = 0.14 N*s, so the bell's surface gets 0.07 m/s.
  EXPECT_NEAR(ding.value("speed"), 0.1 * std::sqrt(2 * 9.81 * 0.1) / 2.0, 0.01);

  SoundResolver& s = sound(w);
  const double rate = s.sample_rate();
  // The strike's advance is the one of the step the event came in: it covers
  // [(k - 1) dt, k dt] after k steps, and the ringing starts at its first sample.
  const double t_ding = double(sound_steps[0] - 1) * w.dt();
  const auto all = s.samples();
  EXPECT_EQ(rms(window(all, rate, 0, t_ding)), 0.0) << "sound before the strike";
  EXPECT_GT(rms(window(all, rate, t_ding, t_ding + 0.002)), 1e-3) << "no sound at the strike";
  const auto after = window(all, rate, t_ding + 0.01, t_ding + 0.21);
  const double at_pitch = goertzel(after, kBellPitch, rate);
  EXPECT_GT(at_pitch, 1e-3);
  for (double f : {kBellPitch * 0.89, kBellPitch * 1.12})
    EXPECT_GT(at_pitch / goertzel(after, f, rate), 30.0) << "at " << f << " Hz";
}

TEST_F(SoundFromCollisionsTest, AHarderFallRingsLouder) {
  std::vector<double> amplitude;
  for (double drop : {0.05, 0.2}) {  // impact speeds 0.99 and 1.98 m/s
    World w(registry);
    sounds.clear(), began_step = 0;
    build(w, drop);
    run(w, 0.5);
    ASSERT_EQ(sounds.size(), 1u) << "drop " << drop;
    amplitude.push_back(sounds[0].value("amplitude"));
  }
  // Four times the height, twice the speed, twice the impulse.
  EXPECT_NEAR(amplitude[1] / amplitude[0], 2.0, 0.15);
}

TEST_F(SoundFromCollisionsTest, APartSetDownGentlyMakesNoSound) {
  World w(registry);
  build(w, 0.0001);  // 0.1 mm: it lands at 0.044 m/s, under the 0.1 m/s threshold
  run(w, 0.5);
  ASSERT_GT(began_step, 0u);
  EXPECT_TRUE(sounds.empty());
  EXPECT_EQ(rms(sound(w).samples()), 0.0);
}

TEST_F(SoundFromCollisionsTest, BothPartsRingIfBothCan) {
  World w(registry);
  build(w, 0.1);
  w.set(ball, "acoustic", std::string("block"));
  w.set(ball, "pitch", 3000.0);
  run(w, 0.3);
  ASSERT_EQ(sounds.size(), 2u);
  EXPECT_EQ(sounds[0].a, bell);
  EXPECT_EQ(sounds[1].a, ball);
  EXPECT_EQ(sounds[1].b, bell);
  EXPECT_EQ(sounds[1].text, "block");
  // The light ball is shaken far harder than the heavy bell (J / m).
  EXPECT_GT(sounds[1].value("speed"), 10 * sounds[0].value("speed"));
}

TEST_F(SoundFromCollisionsTest, ABouncingBallRingsAtEveryBounceSofterEachTime) {
  const double e = 0.6;
  World w(registry);
  build(w, 0.2, e);
  run(w, 1.5);
  // Each bounce leaves at e times the speed it came in with: the next blow
  // is e times as strong, and comes e times as soon.
  // The blow is the collision's impulse m (1 + e) u at the speed u the ball
  // touched with. From the fifth blow on (0.26 m/s) one step's gravity kick
  // (g dt = 0.04 m/s) is 16 % of that speed, and where in the step the touch
  // falls moves the ratio by as much: the first four are held to e.
  ASSERT_GE(sounds.size(), 4u);
  for (std::size_t i = 1; i < 4; ++i)
    EXPECT_NEAR(sounds[i].value("amplitude") / sounds[i - 1].value("amplitude"), e, 0.08) << i;
  for (std::size_t i = 2; i < 4; ++i) {
    const double ratio = double(sound_steps[i] - sound_steps[i - 1]) /
                         double(sound_steps[i - 1] - sound_steps[i - 2]);
    EXPECT_NEAR(ratio, e, 0.08) << i;
  }
}

TEST_F(SoundFromCollisionsTest, NoAcousticPartNoSoundStages) {
  World w(registry);
  build(w, 0.1);
  w.remove(bell, "acoustic");
  run(w, 0.3);
  EXPECT_FALSE(w.has_stage("sound"));
  EXPECT_FALSE(w.has_stage("sound_from_collisions"));
  EXPECT_TRUE(w.has_stage("collisions"));
}

}  // namespace
}  // namespace alloy::sound
