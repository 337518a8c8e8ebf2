// Tests for resolvers/sound/sound_resolver.hpp in a world: a struck bell rings
// at its pitch and decays at its stated rate, the run is silent before the
// strike, louder blows ring louder, soft ones not at all, the buffer stays in
// step with simulated time, and the resolver exists only where a part can ring.
// The test plays the part of an interaction: it queues strikes between steps.
#include "resolvers/sound/sound_resolver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/resolvers/sound/goertzel.hpp"

namespace alloy::sound {
namespace {

using test::goertzel;
using test::rms;
using test::window;

class SoundResolverTest : public ::testing::Test {
 protected:
  void SetUp() override { register_sound_resolver(registry); }

  /// A bell of the given pitch and T60, alone in a world.
  std::unique_ptr<World> bell_world(double pitch = 880, double decay = 2.0, WorldDef def = {}) {
    auto w = std::make_unique<World>(registry, std::move(def));
    bell = w->create("bell");
    w->set(bell, "acoustic",
           *registry.properties().enum_value(registry.properties().id("acoustic"), "bell"));
    w->set(bell, "pitch", pitch);
    w->set(bell, "decay", decay);
    w->start();
    return w;
  }
  static SoundResolver& sound(World& w) { return dynamic_cast<SoundResolver&>(*w.stage("sound")); }
  /// Runs whole seconds of steps.
  static void run_for(World& w, double seconds) {
    w.run(std::uint64_t(std::llround(seconds / w.dt())));
  }

  PluginRegistry registry;
  ObjectId bell;
};

TEST_F(SoundResolverTest, ARunIsSilentUntilSomethingIsStruck) {
  auto w = bell_world();
  run_for(*w, 0.25);
  const auto s = sound(*w).samples();
  ASSERT_EQ(s.size(), 12000u);
  EXPECT_EQ(rms(s), 0.0);
  EXPECT_TRUE(w->events().empty());
}

TEST_F(SoundResolverTest, AStruckBellRingsAtItsPitch) {
  auto w = bell_world(880, 2.0);
  run_for(*w, 0.25);
  sound(*w).strike({.part = bell, .normal_speed = 1.0});
  run_for(*w, 0.5);
  const double rate = sound(*w).sample_rate();
  const auto s = sound(*w).samples();
  EXPECT_EQ(rms(window(s, rate, 0.0, 0.25)), 0.0);  // silence before the strike
  const auto after = window(s, rate, 0.26, 0.46);
  const double at_pitch = goertzel(after, 880, rate);
  // Neighbours: a whole tone either side, and between the partials.
  for (double f : {880 * 0.89, 880 * 1.12, 880 * 0.75, 880 * 1.35, 880 * 1.75}) {
    const double ratio = at_pitch / goertzel(after, f, rate);
    EXPECT_GT(ratio, 30.0) << "at " << f << " Hz";
  }
  // The bell is a bell: its hum and nominal ring too.
  EXPECT_GT(goertzel(after, 440, rate), 0.2 * at_pitch);
  EXPECT_GT(goertzel(after, 1760, rate), 0.2 * at_pitch);
}

TEST_F(SoundResolverTest, TheBellDecaysAtItsStatedRate) {
  const double t60 = 1.5;
  auto w = bell_world(660, t60);
  sound(*w).strike({.part = bell, .normal_speed = 2.0});
  run_for(*w, 1.5);
  const double rate = sound(*w).sample_rate();
  const auto s = sound(*w).samples();
  // The prime's level in two windows 1 s apart falls 60 dB * 1 s / T60 = 40 dB.
  const double early = goertzel(window(s, rate, 0.1, 0.3), 660, rate);
  const double late = goertzel(window(s, rate, 1.1, 1.3), 660, rate);
  const double measured_t60 = 60.0 * 1.0 / (20 * std::log10(early / late));
  EXPECT_NEAR(measured_t60, t60, 0.02 * t60);
}

TEST_F(SoundResolverTest, AHarderBlowRingsLouder) {
  std::vector<double> levels;
  for (double speed : {0.5, 1.0, 2.0}) {
    auto w = bell_world();
    sound(*w).strike({.part = bell, .normal_speed = speed});
    run_for(*w, 0.25);
    levels.push_back(rms(sound(*w).samples()));
  }
  EXPECT_GT(levels[0], 1e-3);
  EXPECT_NEAR(levels[1] / levels[0], 2.0, 1e-3);  // linear in the strike velocity
  EXPECT_NEAR(levels[2] / levels[1], 2.0, 1e-3);
}

TEST_F(SoundResolverTest, ABlowBelowTheThresholdMakesNoSound) {
  auto w = bell_world();
  const double min_speed = sound(*w).settings().min_speed;
  sound(*w).strike({.part = bell, .normal_speed = 0.5 * min_speed});
  w->step();
  EXPECT_TRUE(w->events().empty());
  run_for(*w, 0.25);
  EXPECT_EQ(rms(sound(*w).samples()), 0.0);
  EXPECT_EQ(sound(*w).voice_count(), 0u);
  // Just above it, it does.
  sound(*w).strike({.part = bell, .normal_speed = 1.01 * min_speed});
  w->step();
  ASSERT_EQ(w->events().size(), 1u);
}

TEST_F(SoundResolverTest, AnImpulseThresholdCanBeSet) {
  WorldDef def;
  def.settings["sound"].set("min_impulse", 0.01);
  auto w = bell_world(880, 2.0, def);
  sound(*w).strike({.part = bell, .normal_speed = 1.0, .impulse = 0.005});
  w->step();
  EXPECT_TRUE(w->events().empty());
  sound(*w).strike({.part = bell, .normal_speed = 1.0, .impulse = 0.02});
  w->step();
  EXPECT_EQ(w->events().size(), 1u);
}

TEST_F(SoundResolverTest, AStrikeEmitsASoundEventNamingThePartAndItsPitch) {
  auto w = bell_world(523.25, 2.0);
  const ObjectId striker = w->create("striker");
  sound(*w).strike({.part = bell, .other = striker, .normal_speed = 1.0});
  w->step();  // performed in the next advance (the one-step delay of paper 3.2)
  ASSERT_EQ(w->events().size(), 1u);
  const Event& e = w->events()[0];
  EXPECT_EQ(e.type, "sound");
  EXPECT_EQ(e.source, "sound");
  EXPECT_EQ(e.a, bell);
  EXPECT_EQ(e.b, striker);
  EXPECT_EQ(e.text, "bell");
  EXPECT_DOUBLE_EQ(e.value("pitch"), 523.25);
  EXPECT_DOUBLE_EQ(e.value("amplitude"), kAmplitudePerSpeed * 1.0);
}

TEST_F(SoundResolverTest, ImpulseOverMassSetsTheStrength) {
  // A light striker hardly stirs a heavy part: the surface velocity is J / m.
  registry.properties().add(
      {.name = "mass", .kind = PropertyKind::Number, .unit = "kg", .min = 0.0});
  auto w = bell_world();
  w->set(bell, "mass", 2.0);
  sound(*w).strike({.part = bell, .normal_speed = 1.0, .impulse = 0.1});
  w->step();
  ASSERT_EQ(w->events().size(), 1u);
  EXPECT_DOUBLE_EQ(w->events()[0].value("speed"), 0.05);
}

TEST_F(SoundResolverTest, EachStepAddsExactlyItsShareOfSamples) {
  WorldDef def;
  def.dt = 1.0 / 300;
  def.settings["sound"].set("sample_rate", 44100.0);  // 147 samples a step
  auto w = bell_world(880, 2.0, def);
  w->run(300);
  EXPECT_EQ(sound(*w).samples().size(), 44100u);  // 1 s of simulation = 1 s of sound
  EXPECT_EQ(sound(*w).sample_rate(), 44100.0);
  // An awkward step: the buffer stays within half a sample of simulated time.
  WorldDef odd;
  odd.dt = 1.0 / 237;
  auto w2 = bell_world(880, 2.0, odd);
  w2->run(1000);
  EXPECT_EQ(double(sound(*w2).samples_produced()), std::round(1000.0 / 237 * 48000));
  EXPECT_DOUBLE_EQ(sound(*w2).start_time(), 0.0);
}

TEST_F(SoundResolverTest, TakeSamplesHandsOverTheBuffer) {
  auto w = bell_world();
  w->run(10);
  const auto taken = sound(*w).take_samples();
  EXPECT_EQ(taken.size(), 2000u);
  EXPECT_TRUE(sound(*w).samples().empty());
  w->run(5);
  EXPECT_EQ(sound(*w).samples().size(), 1000u);
  EXPECT_EQ(sound(*w).samples_produced(), 3000u);
}

TEST_F(SoundResolverTest, IsInstantiatedOnlyWhenAPartCanRing) {
  World w(registry);
  const ObjectId mute = w.create("mute");
  w.set(mute, "pitch", 440.0);  // a pitch alone does not make a part ring
  w.run(3);
  EXPECT_FALSE(w.has_stage("sound"));
  w.set(mute, "acoustic",
        *registry.properties().enum_value(registry.properties().id("acoustic"), "bar"));
  w.step();
  ASSERT_TRUE(w.has_stage("sound"));
  // It joined a running world: its first sample is at the time it started.
  EXPECT_DOUBLE_EQ(sound(w).start_time(), 3 * w.dt());
  EXPECT_EQ(sound(w).samples().size(), 200u);
}

TEST_F(SoundResolverTest, ABarsPitchComesFromItsMaterialAndSize) {
  // The rigid body's shape properties, as it registers them.
  auto& props = registry.properties();
  props.add(
      {.name = "shape", .kind = PropertyKind::Enum, .enum_values = {"box", "sphere", "capsule"}});
  props.add({.name = "size", .kind = PropertyKind::Vec3, .unit = "m"});
  World w(registry);
  const ObjectId bar = w.create("bar");
  w.set(bar, "acoustic", *props.enum_value(props.id("acoustic"), "bar"));
  w.set(bar, "shape", *props.enum_value(props.id("shape"), "box"));
  w.set(bar, "size", Vec3{0.3, 0.02, 0.01});
  w.set(bar, "youngs_modulus", 2e11);
  w.set(bar, "density", 7850.0);
  w.set(bar, "loss_factor", 2e-3);
  w.start();
  const auto v = SoundResolver::voicing(w.view(), bar);
  EXPECT_NEAR(v.pitch, 576.5, 0.5);  // see AcousticModel.SteelBarFirstBendingMode
  EXPECT_NEAR(v.decay, kLn1000 / (M_PI * v.pitch * 2e-3), 1e-9);
  // And the samples say so.
  sound(w).strike({.part = bar, .normal_speed = 1.0});
  run_for(w, 0.3);
  const auto s = window(sound(w).samples(), 48000, 0.05, 0.25);
  EXPECT_GT(goertzel(s, v.pitch, 48000) / goertzel(s, v.pitch * 1.1, 48000), 30.0);
  EXPECT_GT(goertzel(s, v.pitch * 2.7565, 48000), 0.1 * goertzel(s, v.pitch, 48000));
}

TEST_F(SoundResolverTest, WithoutPitchOrMaterialAFamilyDefaultIsUsed) {
  World w(registry);
  const ObjectId block = w.create("block");
  w.set(block, "acoustic",
        *registry.properties().enum_value(registry.properties().id("acoustic"), "block"));
  w.start();
  const auto v = SoundResolver::voicing(w.view(), block);
  EXPECT_EQ(v.family, Family::block);
  EXPECT_DOUBLE_EQ(v.pitch, default_pitch(Family::block));
  EXPECT_DOUBLE_EQ(v.decay, default_decay(Family::block));
}

TEST_F(SoundResolverTest, AStrikeOnAPartDestroyedMeanwhileIsDropped) {
  auto w = bell_world();
  sound(*w).strike({.part = bell, .normal_speed = 1.0});
  w->destroy(bell);
  EXPECT_NO_THROW(w->step());
  EXPECT_TRUE(w->events().empty());
}

TEST_F(SoundResolverTest, BadSettingsAreRefusedByName) {
  WorldDef def;
  def.settings["sound"].set("sample_rate", 1000.0);
  EXPECT_THROW(bell_world(880, 2, def), InputError);
  WorldDef typo;
  typo.settings["sound"].set("min_sped", 1.0);
  try {
    bell_world(880, 2, typo);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("min_sped"), std::string::npos);
  }
}

TEST_F(SoundResolverTest, SameStrikesGiveBitIdenticalSamples) {
  auto run = [&] {
    auto w = bell_world(700, 1.0);
    for (int i = 0; i < 5; ++i) {
      sound(*w).strike({.part = bell, .normal_speed = 0.3 + 0.2 * i});
      w->run(37);
    }
    const auto s = sound(*w).samples();
    return std::vector<float>(s.begin(), s.end());
  };
  EXPECT_EQ(run(), run());
}

}  // namespace
}  // namespace alloy::sound
