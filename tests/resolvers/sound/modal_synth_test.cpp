// Tests for resolvers/sound/modal_synth.hpp: a mode sounds at its frequency,
// decays at its T60, starts from zero, and modes that would alias are dropped.
#include "resolvers/sound/modal_synth.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/resolvers/sound/goertzel.hpp"

namespace alloy::sound {
namespace {

using test::goertzel;

constexpr double kRate = 48000;

std::vector<float> render(ModalSynth& synth, double seconds) {
  std::vector<float> out(std::size_t(seconds * kRate), 0.0f);
  synth.render(out);
  return out;
}

TEST(ModalSynth, IsSilentWithoutAStrike) {
  ModalSynth synth({.sample_rate = kRate});
  const auto out = render(synth, 0.1);
  for (float s : out) ASSERT_EQ(s, 0.0f);
}

TEST(ModalSynth, OneModeIsADecayingSinusoidStartingAtZero) {
  ModalSynth synth({.sample_rate = kRate});
  const Mode m{.frequency = 1000, .amplitude = 0.5, .t60 = 0.5};
  synth.strike(std::span(&m, 1));
  const auto out = render(synth, 0.2);
  // Sample k is A e^{-a t} sin(w t) at t = (k + 1) / rate, exactly up to rounding.
  const double a = kLn1000 / m.t60;
  for (std::size_t k : {0u, 1u, 47u, 4800u, 9599u}) {
    const double t = double(k + 1) / kRate;
    EXPECT_NEAR(out[k], 0.5 * std::exp(-a * t) * std::sin(2 * M_PI * 1000 * t), 1e-6) << k;
  }
  EXPECT_LT(std::abs(out[0]), 0.07);  // no click at the strike
}

TEST(ModalSynth, AmplitudeFallsSixtyDecibelsInT60) {
  ModalSynth synth({.sample_rate = kRate});
  const Mode m{.frequency = 700, .amplitude = 1, .t60 = 0.3};
  synth.strike(std::span(&m, 1));
  const auto out = render(synth, 0.5);
  const std::span<const float> s(out);
  const double early = goertzel(test::window(s, kRate, 0.0, 0.05), 700, kRate);
  const double late = goertzel(test::window(s, kRate, 0.3, 0.35), 700, kRate);
  EXPECT_NEAR(20 * std::log10(early / late), 60.0, 0.5);
}

TEST(ModalSynth, ModesThatWouldAliasAreLeftOut) {
  ModalSynth synth({.sample_rate = kRate});
  const Mode above{.frequency = 30000, .amplitude = 1, .t60 = 1};
  synth.strike(std::span(&above, 1));
  EXPECT_EQ(synth.voice_count(), 0u);
  const auto out = render(synth, 0.01);
  EXPECT_EQ(test::rms(out), 0.0);
}

TEST(ModalSynth, VoicesEndWhenTheyFallBelowTheFloor) {
  ModalSynth synth({.sample_rate = kRate});
  const Mode m{.frequency = 500, .amplitude = 1, .t60 = 0.1};  // -120 dB after 0.2 s
  synth.strike(std::span(&m, 1));
  render(synth, 0.1);
  EXPECT_EQ(synth.voice_count(), 1u);
  render(synth, 0.15);
  EXPECT_EQ(synth.voice_count(), 0u);
}

TEST(ModalSynth, AFullSynthReplacesItsQuietestVoice) {
  ModalSynth synth({.sample_rate = kRate, .max_voices = 2});
  const Mode loud{.frequency = 500, .amplitude = 1, .t60 = 5};
  const Mode quiet{.frequency = 600, .amplitude = 0.01, .t60 = 5};
  const Mode third{.frequency = 900, .amplitude = 0.5, .t60 = 5};
  synth.strike(std::span(&loud, 1));
  synth.strike(std::span(&quiet, 1));
  synth.strike(std::span(&third, 1));
  EXPECT_EQ(synth.voice_count(), 2u);
  const auto out = render(synth, 0.1);
  EXPECT_GT(goertzel(out, 500, kRate), 0.5);
  EXPECT_GT(goertzel(out, 900, kRate), 0.2);
  EXPECT_LT(goertzel(out, 600, kRate), 1e-4);  // the quiet one was dropped
}

}  // namespace
}  // namespace alloy::sound
