// What the sound resolver synthesised, played through SDL2 audio. The
// resolver makes samples in step with the simulation; each frame the viewer
// hands over what the frame's steps made, and SDL plays it from a queue.
#pragma once

#include <SDL.h>

#include <cstdint>
#include <string>

#include "runtime/world.hpp"

namespace alloy::viewer {

class AudioOut {
 public:
  AudioOut() = default;
  ~AudioOut();
  AudioOut(const AudioOut&) = delete;
  AudioOut& operator=(const AudioOut&) = delete;

  /// Opens the default output at `rate` Hz, mono float; false (and why) if
  /// there is none: the viewer then runs silent.
  bool open(double rate, std::string* why);
  bool is_open() const { return device_ != 0; }
  /// Takes the samples the world's sound resolver made since the last call
  /// and queues them. Muted or closed: the samples are still taken (so that
  /// the buffer does not grow) and dropped.
  void pump(World& world, bool muted);
  /// Samples taken from the world so far.
  std::uint64_t samples_taken() const { return taken_; }
  /// Peak |sample| of everything taken so far (tests: did it ring?).
  float peak() const { return peak_; }

 private:
  SDL_AudioDeviceID device_ = 0;
  bool subsystem_ = false;
  double rate_ = 0;
  std::uint64_t taken_ = 0;
  float peak_ = 0;
};

}  // namespace alloy::viewer
