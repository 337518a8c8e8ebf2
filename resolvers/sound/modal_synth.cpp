#include "resolvers/sound/modal_synth.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace alloy::sound {

ModalSynth::ModalSynth(Settings settings) : settings_(settings) {
  if (!(settings_.sample_rate > 0)) throw std::invalid_argument("sample rate must be positive");
  if (settings_.max_voices == 0) settings_.max_voices = 1;
}

double ModalSynth::Voice::level() const {
  double sum = 0;
  for (const Oscillator& o : oscillators) sum += std::abs(o.z);
  return sum;
}

void ModalSynth::strike(std::span<const Mode> modes) {
  const double fs = settings_.sample_rate;
  Voice voice;
  for (const Mode& m : modes) {
    if (!(m.frequency > 0) || m.frequency >= 0.45 * fs) continue;
    if (!(std::abs(m.amplitude) > settings_.floor) || !(m.t60 > 0)) continue;
    const double decay_per_sample = std::exp(-kLn1000 / (m.t60 * fs));
    const double w = 2 * std::numbers::pi * m.frequency / fs;
    // z starts at amplitude on the real axis; after the first turn its
    // imaginary part is A r sin(w): the first sample is one sample after the
    // strike, so the output is A e^{-a t} sin(w t) at t = 1/fs, 2/fs, ...
    voice.oscillators.push_back({std::complex<double>(m.amplitude, 0),
                                 std::polar(decay_per_sample, w)});
  }
  if (voice.oscillators.empty()) return;
  if (voices_.size() >= settings_.max_voices) {
    auto quietest = std::min_element(voices_.begin(), voices_.end(), [](const Voice& a, const Voice& b) {
      return a.level() < b.level();
    });
    *quietest = std::move(voice);
    return;
  }
  voices_.push_back(std::move(voice));
}

void ModalSynth::render(std::span<float> out) {
  if (voices_.empty() || out.empty()) return;
  for (Voice& v : voices_) {
    for (Oscillator& o : v.oscillators) {
      // Local copies keep the inner loop in registers.
      std::complex<double> z = o.z;
      const std::complex<double> turn = o.turn;
      for (float& s : out) {
        z *= turn;
        s += float(z.imag());
      }
      o.z = z;
    }
    const double floor = settings_.floor;
    std::erase_if(v.oscillators, [floor](const Oscillator& o) { return std::abs(o.z) < floor; });
  }
  std::erase_if(voices_, [](const Voice& v) { return v.oscillators.empty(); });
}

}  // namespace alloy::sound
