// Modal synthesis: a struck object sounds as a sum of exponentially decaying
// sinusoids, one per vibration mode (van den Doel and Pai, "The sounds of
// physical shapes", 1998). No sample files: a bell, a bar and a wood block
// differ only in their list of modes.
//
// Each mode is a complex phasor turned by a fixed complex factor per sample
// (z <- z * r e^{i w / fs}), so a mode costs one complex multiply per sample
// (no sin, no exp in the loop) and is exact to rounding: the decay rate and frequency a test
// measures are the ones that were asked for. Pure DSP: no world, no properties.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace alloy::sound {

/// One vibration mode as it is heard: a sinusoid that starts at zero phase
/// (a struck body starts from rest, so there is no click) and decays
/// exponentially.
struct Mode {
  double frequency = 440;  ///< Hz
  double amplitude = 0;    ///< peak of the sinusoid at the strike, full scale = 1
  double t60 = 1;          ///< s for the amplitude to fall by 60 dB (a factor of 1000)
};

/// ln(1000): an amplitude envelope exp(-a t) falls 60 dB in T60 = ln(1000) / a.
inline constexpr double kLn1000 = 6.907755278982137;

/// The voices that ring now, and the mixing of them into samples.
class ModalSynth {
 public:
  struct Settings {
    double sample_rate = 48000;  ///< Hz
    /// Voices beyond this replace the quietest one (bounds the cost of a
    /// machine-gun of strikes; the quietest voice is the one least missed).
    std::size_t max_voices = 32;
    /// A mode below this amplitude (full scale = 1) is dropped: -120 dB, far
    /// below a 16-bit file's least significant bit (3e-5).
    double floor = 1e-6;
  };

  explicit ModalSynth(Settings settings);

  /// Starts a voice made of `modes`. Modes at or above 0.45 * sample rate are
  /// left out: they would alias into the audible band.
  void strike(std::span<const Mode> modes);

  /// Adds the next `out.size()` samples of every ringing voice to `out`.
  void render(std::span<float> out);

  std::size_t voice_count() const { return voices_.size(); }
  /// The voices in flight as numbers, for a snapshot: per voice its mode
  /// count, then each mode's state (re, im) and rotation (cr, ci), exact bits.
  std::vector<double> voices_state() const;
  /// Puts back what voices_state() gave. Returns false (and changes nothing)
  /// if the numbers do not describe voices (a damaged snapshot).
  bool set_voices_state(const std::vector<double>& state);
  const Settings& settings() const { return settings_; }

 private:
  // A voice's modes as parallel arrays: the phasor z = (re, im) of each mode,
  // and its per-sample turn (cr, ci) = r e^{i w / fs}. The output is im.
  // Plain arithmetic, not std::complex: its multiplication must recover from
  // NaN and inf (a library call per sample), which made rendering 2.5x slower.
  struct Voice {
    std::vector<double> re, im, cr, ci;
    std::size_t size() const { return re.size(); }
    double level() const;  // sum of current mode amplitudes, for voice stealing
  };

  Settings settings_;
  std::vector<Voice> voices_;
};

}  // namespace alloy::sound
