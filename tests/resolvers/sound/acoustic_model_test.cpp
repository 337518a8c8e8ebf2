// Tests for resolvers/sound/acoustic_model.hpp: the pitch formulas against
// hand calculations, and the loss-factor decay law.
#include "resolvers/sound/acoustic_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace alloy::sound {
namespace {

TEST(AcousticModel, SteelBarFirstBendingMode) {
  // A 0.3 m steel bar, 10 mm thick: f1 = 22.373 / (2 pi 0.09) * (0.01 / sqrt 12)
  // * sqrt(2e11 / 7850) = 39.565 * 0.0028868 * 5047.5 = 576.5 Hz.
  const double f = bar_pitch(2e11, 7850, 0.3, 0.01 / std::sqrt(12.0));
  EXPECT_NEAR(f, 576.5, 0.5);
  // Twice as long: a quarter of the pitch; twice as thick: twice the pitch.
  EXPECT_NEAR(bar_pitch(2e11, 7850, 0.6, 0.01 / std::sqrt(12.0)), f / 4, 1e-9);
  EXPECT_NEAR(bar_pitch(2e11, 7850, 0.3, 0.02 / std::sqrt(12.0)), 2 * f, 1e-9);
}

TEST(AcousticModel, CircularPlateMode) {
  // Bronze, radius 0.05 m, 3 mm thick: D = 1.1e11 * 2.7e-8 / (12 * 0.91) = 271.98 N*m,
  // f = 5.253 / (2 pi 0.0025) * sqrt(271.98 / (8600 * 0.003)) = 334.42 * 3.2468 = 1085.8 Hz.
  EXPECT_NEAR(plate_pitch(1.1e11, 8600, 0.05, 0.003), 1085.8, 1.0);
}

TEST(AcousticModel, LossFactorGivesT60InverseToFrequency) {
  EXPECT_NEAR(decay_from_loss_factor(1000, 1e-3), kLn1000 / (M_PI * 1.0), 1e-12);
  EXPECT_NEAR(decay_from_loss_factor(2000, 1e-3), decay_from_loss_factor(1000, 1e-3) / 2, 1e-12);
}

TEST(AcousticModel, BellPartialsAreTheFoundersRatios) {
  const auto modes = modes_of(Family::bell, 800, 3.0, 0.5);
  ASSERT_GE(modes.size(), 5u);
  const double ratios[] = {0.5, 1.0, 1.2, 1.5, 2.0};  // hum, prime, tierce, quint, nominal
  for (int i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(modes[i].frequency, 800 * ratios[i]);
  EXPECT_DOUBLE_EQ(modes[1].amplitude, 0.5);  // the prime carries the given amplitude
  EXPECT_DOUBLE_EQ(modes[1].t60, 3.0);        // and the given decay
  EXPECT_DOUBLE_EQ(modes[4].t60, 1.5);        // the nominal dies twice as fast
  EXPECT_DOUBLE_EQ(modes[0].t60, 6.0);        // the hum rings longest
}

TEST(AcousticModel, EveryFamilyHasANameAndStartsAtItsFundamental) {
  for (auto f : {Family::bell, Family::bar, Family::block}) {
    EXPECT_FALSE(family_names()[std::size_t(f)].empty());
    bool has_fundamental = false;
    for (const Partial& p : partials(f)) has_fundamental |= p.ratio == 1.0 && p.amplitude == 1.0;
    EXPECT_TRUE(has_fundamental);
    EXPECT_GT(default_pitch(f), 20);
    EXPECT_GT(default_decay(f), 0);
  }
}

}  // namespace
}  // namespace alloy::sound
