// What a struck part sounds like, from what it is made of and its shape.
//
// A part belongs to one family of vibrating bodies, which fixes the ratios of
// its mode frequencies to the fundamental and their relative strengths:
//
//   bell   the partials of a tuned church bell, named by bell founders:
//          hum 0.5, prime 1, tierce 1.2 (minor third), quint 1.5, nominal 2,
//          and the weaker upper partials. `pitch` is the prime.
//   bar    the bending modes of a free-free Euler-Bernoulli beam (a
//          glockenspiel bar, a kit bar): 1, 2.756, 5.404, 8.933.
//   block  a short, inharmonic "clack" (a wood block, a striker): few modes,
//          heavily damped.
//
// The fundamental is the part's `pitch` if it has one; otherwise it is
// computed from the material (Young's modulus, density) and the part's size
// (bar: first free-free bending mode; bell: the (2,0) mode of a free circular
// plate, the bell's own lowest shell mode in the flat limit); otherwise a
// family default. Decay follows a constant material loss factor eta: every
// mode loses the same fraction of its energy per cycle, so T60 = ln(1000) /
// (pi f eta) and higher modes die faster, as in real metal and wood.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "resolvers/sound/modal_synth.hpp"

namespace alloy::sound {

/// The values of the `acoustic` enum property, in order.
enum class Family : std::int32_t { bell = 0, bar = 1, block = 2 };
/// The names of the `acoustic` enum values, index = Family.
const std::vector<std::string>& family_names();

/// A mode of a family, relative to the fundamental.
struct Partial {
  double ratio;      ///< frequency / fundamental
  double amplitude;  ///< amplitude / the fundamental's amplitude
};
std::span<const Partial> partials(Family family);

/// Fundamental when neither `pitch` nor material and size are known, Hz.
double default_pitch(Family family);
/// T60 of the fundamental when neither `decay` nor `loss_factor` is known, s.
double default_decay(Family family);

/// Poisson's ratio assumed for plates (metals are 0.28 to 0.35).
inline constexpr double kPoisson = 0.3;

/// First bending mode of a free-free bar (Euler-Bernoulli), Hz:
/// f1 = (4.730^2 / (2 pi L^2)) * k * sqrt(E / rho), with `length` L and
/// `gyration` k = sqrt(I / A), the radius of gyration of the cross-section
/// about the bending axis, in m: h / sqrt(12) for a rectangular bar of
/// thickness h, d / 4 for a round rod of diameter d.
double bar_pitch(double youngs_modulus, double density, double length, double gyration);

/// Lowest (2,0) mode of a free circular plate of radius a and thickness h, Hz:
/// f = (5.253 / (2 pi a^2)) * sqrt(D / (rho h)), D = E h^3 / (12 (1 - nu^2)).
/// A bell is a curved shell and rings higher than the flat plate of its
/// mouth; give `pitch` to tune a bell exactly.
double plate_pitch(double youngs_modulus, double density, double radius, double thickness);

/// T60 of a mode of frequency f in a material of loss factor eta, s.
double decay_from_loss_factor(double frequency, double loss_factor);

/// The modes heard when a part of `family` with fundamental `pitch` (Hz) and
/// fundamental T60 `decay` (s) is struck so that its fundamental starts at
/// `amplitude` (full scale = 1). Each mode keeps the loss factor of the
/// fundamental: T60_k = decay * pitch / f_k.
std::vector<Mode> modes_of(Family family, double pitch, double decay, double amplitude);

}  // namespace alloy::sound
