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
  for (std::size_t k = 0; k < size(); ++k) sum += std::hypot(re[k], im[k]);
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
    voice.re.push_back(m.amplitude);
    voice.im.push_back(0);
    voice.cr.push_back(decay_per_sample * std::cos(w));
    voice.ci.push_back(decay_per_sample * std::sin(w));
  }
  if (voice.size() == 0) return;
  if (voices_.size() >= settings_.max_voices) {
    auto quietest =
        std::min_element(voices_.begin(), voices_.end(),
                         [](const Voice& a, const Voice& b) { return a.level() < b.level(); });
    *quietest = std::move(voice);
    return;
  }
  voices_.push_back(std::move(voice));
}

void ModalSynth::render(std::span<float> out) {
  if (voices_.empty() || out.empty()) return;
  for (Voice& v : voices_) {
    const std::size_t n = v.size();
    double* re = v.re.data();
    double* im = v.im.data();
    const double* cr = v.cr.data();
    const double* ci = v.ci.data();
    for (float& s : out) {
      double sum = 0;
      for (std::size_t k = 0; k < n; ++k) {  // independent modes: no chain between them
        const double r = re[k] * cr[k] - im[k] * ci[k];
        const double i = re[k] * ci[k] + im[k] * cr[k];
        re[k] = r;
        im[k] = i;
        sum += i;
      }
      s += float(sum);
    }
    // Drop the modes that fell below the floor, keeping the arrays parallel.
    std::size_t kept = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (std::hypot(re[k], im[k]) < settings_.floor) continue;
      v.re[kept] = v.re[k], v.im[kept] = v.im[k], v.cr[kept] = v.cr[k], v.ci[kept] = v.ci[k];
      ++kept;
    }
    v.re.resize(kept), v.im.resize(kept), v.cr.resize(kept), v.ci.resize(kept);
  }
  std::erase_if(voices_, [](const Voice& v) { return v.size() == 0; });
}

std::vector<double> ModalSynth::voices_state() const {
  std::vector<double> out;
  for (const Voice& v : voices_) {
    out.push_back(double(v.size()));
    for (std::size_t k = 0; k < v.size(); ++k)
      out.insert(out.end(), {v.re[k], v.im[k], v.cr[k], v.ci[k]});
  }
  return out;
}

bool ModalSynth::set_voices_state(const std::vector<double>& state) {
  std::vector<Voice> voices;
  for (std::size_t at = 0; at < state.size();) {
    const double n = state[at++];
    // A voice has at least one mode (empty ones are dropped as they fall
    // silent) and its modes must be there.
    if (!(n >= 1) || n != std::floor(n) || n > double(state.size() - at) / 4) return false;
    Voice v;
    for (std::size_t k = 0; k < std::size_t(n); ++k, at += 4) {
      v.re.push_back(state[at]), v.im.push_back(state[at + 1]);
      v.cr.push_back(state[at + 2]), v.ci.push_back(state[at + 3]);
    }
    voices.push_back(std::move(v));
  }
  if (voices.size() > settings_.max_voices) return false;
  voices_ = std::move(voices);
  return true;
}

}  // namespace alloy::sound
