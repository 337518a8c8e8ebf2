// The magnet layouts that the summation tests (pole_tree_test, fmm_test,
// fast_summation_test) and bench/scaling.cpp share, so that a figure in the
// bench and a bound in a test are about the same configuration: each builder
// used to be written out in every file (close15.md, "Noticed").
//
// A layout is a list of bars (centre, unit axis, pole strength); each user
// turns them into its own kind of poles or bodies.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "runtime/math.hpp"

namespace alloy::layouts {

/// One bar magnet: poles +strength at centre + axis * separation / 2 and
/// -strength at centre - axis * separation / 2.
struct Bar {
  Vec3 centre;
  Vec3 axis;  ///< unit length
  double strength = 0;
};

/// The kit bars' pole separation, m.
inline constexpr double kBarSeparation = 0.085;

/// A direction uniform on the sphere.
inline Vec3 random_direction(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double z = 2 * u(rng) - 1, phi = 2 * std::numbers::pi * u(rng);
  const double s = std::sqrt(1 - z * z);
  return {s * std::cos(phi), s * std::sin(phi), z};
}

/// n kit bars (50 to 150 A*m, either sign) at uniform random places in a cube
/// holding one bar per (0.15 m)^3, pointing anywhere.
inline std::vector<Bar> random_bars(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const double side = 0.15 * std::cbrt(double(n));
  std::vector<Bar> bars;
  bars.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 c{side * u(rng), side * u(rng), side * u(rng)};
    const Vec3 axis = random_direction(rng);
    const double size = 50 + 100 * u(rng);  // drawn in this order, then the sign
    const double sign = u(rng) < 0.5 ? -1 : 1;
    bars.push_back({c, axis, size * sign});
  }
  return bars;
}

/// Bars 10 cm x 2 cm x 2 cm packed end to end and side by side (a block of
/// nx x ny x nz), all magnetised along x at 100 A*m like a stack of real
/// magnets: near poles nearly cancel and each bar's net force is a small
/// difference of large pole forces (the hard case for expansions).
inline std::vector<Bar> packed_bars(int nx, int ny, int nz) {
  std::vector<Bar> bars;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) bars.push_back({{0.1 * i, 0.02 * j, 0.02 * k}, {1, 0, 0}, 100});
  return bars;
}

}  // namespace alloy::layouts
