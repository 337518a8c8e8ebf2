#include "resolvers/sound/acoustic_model.hpp"

#include <cmath>
#include <numbers>

namespace alloy::sound {

namespace {

// Minor-third church bell: the five partials founders tune (hum, prime,
// tierce, quint, nominal; T. D. Rossing, "Science of Percussion Instruments",
// on bells) plus the strongest upper ones. The strengths are a plausible
// balance, not a measurement of one bell.
constexpr Partial kBell[] = {
    {0.5, 0.6},   // hum
    {1.0, 1.0},   // prime (strike note region; the `pitch`)
    {1.2, 0.55},  // tierce
    {1.5, 0.3},   // quint
    {2.0, 0.7},   // nominal
    {2.5, 0.3},   // deciem
    {3.0, 0.2},   // twelfth
    {4.0, 0.12},  // upper octave
};

// Free-free beam: (beta_n L)^2 = 22.373, 61.673, 120.903, 199.859, divided by
// the first. A central strike excites the even-shaped modes most.
constexpr Partial kBar[] = {
    {1.0, 1.0},
    {2.7565, 0.45},
    {5.4039, 0.3},
    {8.9330, 0.15},
};

// A block struck on a face: a few inharmonic low modes of a thick plate.
constexpr Partial kBlock[] = {
    {1.0, 1.0},
    {1.58, 0.6},
    {2.24, 0.4},
    {3.10, 0.25},
};

}  // namespace

const std::vector<std::string>& family_names() {
  static const std::vector<std::string> names = {"bell", "bar", "block"};
  return names;
}

std::span<const Partial> partials(Family family) {
  switch (family) {
    case Family::bell:
      return kBell;
    case Family::bar:
      return kBar;
    case Family::block:
      return kBlock;
  }
  return kBar;
}

double default_pitch(Family family) {
  switch (family) {
    case Family::bell:
      return 880;  // a small hand bell (A5)
    case Family::bar:
      return 440;
    case Family::block:
      return 1200;  // a wood block
  }
  return 440;
}

double default_decay(Family family) {
  switch (family) {
    case Family::bell:
      return 4.0;
    case Family::bar:
      return 1.5;
    case Family::block:
      return 0.08;
  }
  return 1.0;
}

double bar_pitch(double youngs_modulus, double density, double length, double gyration) {
  constexpr double kBeta1L2 = 22.3733;  // (4.7300)^2
  return kBeta1L2 / (2 * std::numbers::pi * length * length) * gyration *
         std::sqrt(youngs_modulus / density);
}

double plate_pitch(double youngs_modulus, double density, double radius, double thickness) {
  constexpr double kLambda2 = 5.253;  // (2,0) mode of a free circular plate (Leissa)
  const double rigidity =
      youngs_modulus * thickness * thickness * thickness / (12 * (1 - kPoisson * kPoisson));
  return kLambda2 / (2 * std::numbers::pi * radius * radius) *
         std::sqrt(rigidity / (density * thickness));
}

double decay_from_loss_factor(double frequency, double loss_factor) {
  // Energy lost per radian is eta, so the amplitude envelope is
  // exp(-pi f eta t) and it falls 60 dB in ln(1000) / (pi f eta).
  return kLn1000 / (std::numbers::pi * frequency * loss_factor);
}

std::vector<Mode> modes_of(Family family, double pitch, double decay, double amplitude) {
  std::vector<Mode> out;
  for (const Partial& p : partials(family))
    out.push_back({.frequency = pitch * p.ratio,
                   .amplitude = amplitude * p.amplitude,
                   .t60 = decay / p.ratio});
  return out;
}

}  // namespace alloy::sound
