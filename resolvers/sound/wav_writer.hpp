// Writes the synthesised sound of a run as a WAV file: RIFF/WAVE, PCM, 16-bit
// signed little-endian, mono. Written whole: the bytes go to a temporary file
// beside the target, which is then renamed over it, so a reader (or a crash)
// never sees half a file.
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace alloy::sound {

/// What to do with samples outside [-1, 1].
enum class WavLevel {
  clip,  ///< clamp each sample to [-1, 1] (the buffer is what was heard)
  fit,   ///< if the peak exceeds 1, scale everything down so that it is 1
};

/// What was written.
struct WavInfo {
  std::uint64_t frames = 0;   ///< samples written (mono: one per frame)
  double peak = 0;            ///< largest |sample| of the input
  double scale = 1;           ///< factor applied before quantising (fit < 1 if it scaled)
  std::uint64_t clipped = 0;  ///< samples clamped (clip only)
};

/// Writes `samples` (full scale = 1) at `sample_rate` Hz to `path`. Throws
/// std::runtime_error naming the path if the file cannot be written; the
/// target is then left as it was.
WavInfo write_wav(const std::string& path, std::span<const float> samples, int sample_rate,
                  WavLevel level = WavLevel::clip);

}  // namespace alloy::sound
