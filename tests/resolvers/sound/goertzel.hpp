// Test helpers: measure what a sample buffer sounds like.
#pragma once

#include <cmath>
#include <numbers>
#include <span>

namespace alloy::sound::test {

/// Amplitude of the component at `frequency` Hz in `x`, by the Goertzel
/// algorithm over a Hann window. Normalised so that a steady sinusoid of
/// amplitude A reads A (for a window of many periods).
inline double goertzel(std::span<const float> x, double frequency, double sample_rate) {
  const std::size_t n = x.size();
  if (n < 2) return 0;
  const double w = 2 * std::numbers::pi * frequency / sample_rate;
  const double coeff = 2 * std::cos(w);
  double s1 = 0, s2 = 0, window_sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double hann = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * double(i) / double(n - 1));
    window_sum += hann;
    const double s = hann * double(x[i]) + coeff * s1 - s2;
    s2 = s1;
    s1 = s;
  }
  const double power = s1 * s1 + s2 * s2 - coeff * s1 * s2;
  return 2 * std::sqrt(std::max(power, 0.0)) / window_sum;
}

/// Root mean square of `x`.
inline double rms(std::span<const float> x) {
  if (x.empty()) return 0;
  double sum = 0;
  for (float v : x) sum += double(v) * double(v);
  return std::sqrt(sum / double(x.size()));
}

/// The samples of `x` between times t0 and t1 (s from the first sample).
inline std::span<const float> window(std::span<const float> x, double rate, double t0, double t1) {
  const auto a = std::size_t(std::llround(t0 * rate)), b = std::size_t(std::llround(t1 * rate));
  return x.subspan(a, b - a);
}

}  // namespace alloy::sound::test
