#include "apps/viewer/audio_out.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "resolvers/sound/sound_resolver.hpp"

namespace alloy::viewer {

AudioOut::~AudioOut() {
  if (device_) SDL_CloseAudioDevice(device_);
  if (subsystem_) SDL_QuitSubSystem(SDL_INIT_AUDIO);
}

bool AudioOut::open(double rate, std::string* why) {
  if (device_) return true;
  if (!subsystem_) {
    if (SDL_InitSubSystem(SDL_INIT_AUDIO) != 0) {
      if (why) *why = SDL_GetError();
      return false;
    }
    subsystem_ = true;
  }
  SDL_AudioSpec want{}, have{};
  want.freq = int(rate);
  want.format = AUDIO_F32SYS;
  want.channels = 1;
  want.samples = 1024;
  device_ = SDL_OpenAudioDevice(nullptr, 0, &want, &have, 0);
  if (!device_) {
    if (why) *why = SDL_GetError();
    return false;
  }
  rate_ = rate;
  SDL_PauseAudioDevice(device_, 0);
  return true;
}

void AudioOut::pump(World& world, bool muted) {
  auto* sound = dynamic_cast<sound::SoundResolver*>(world.stage("sound"));
  if (!sound) return;
  std::vector<float> samples = sound->take_samples();
  taken_ += samples.size();
  for (float& s : samples) {
    peak_ = std::max(peak_, std::abs(s));
    s = std::clamp(s, -1.0f, 1.0f);  // the resolver does not clip; the speaker must
  }
  if (!device_ || muted || samples.empty()) return;
  // More than a quarter of a second queued (slow motion, a stall): start
  // afresh rather than lag behind the picture.
  if (SDL_GetQueuedAudioSize(device_) > Uint32(rate_ * sizeof(float) / 4))
    SDL_ClearQueuedAudio(device_);
  SDL_QueueAudio(device_, samples.data(), Uint32(samples.size() * sizeof(float)));
}

}  // namespace alloy::viewer
