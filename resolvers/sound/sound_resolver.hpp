// The sound resolver: parts that are struck ring, and the run is heard.
//
// Interaction function: strike(). An interaction (sound_from_collisions) or a
// test queues strikes; the next advance() performs them: it reads the struck
// part's acoustic properties, starts a voice of decaying modes (modal
// synthesis, see acoustic_model.hpp), emits a `sound` event, and then
// synthesises exactly dt worth of samples into the run's buffer. Audio is
// therefore in step with the simulation: sample k of the buffer is the sound
// at world time start_time() + k / sample_rate(), whatever the wall clock did.
//
// State: the ringing voices are transient output, like the samples, not world
// state. Nothing the rest of the world reads depends on them, so the resolver
// writes no property; a rebuild (objects added or removed) keeps the voices
// ringing, and a swapped-in resolver would start silent and lose nothing but
// the tail of the sound. Everything that decides *what* a strike sounds like
// lives in properties (acoustic, pitch, decay, ...) and is read at the strike.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "resolvers/sound/acoustic_model.hpp"
#include "resolvers/sound/modal_synth.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/world.hpp"

namespace alloy::sound {

/// Property types of sound (owner "sound"). `density` is shared with the
/// rigid body and defined identically (kg/m^3, >= 0).
std::vector<PropertyDef> sound_properties();

/// Settings of the `sound` plugin, with their defaults. A scene sets them as
/// `sound { sample_rate = 44100, min_speed = 0.2 }`.
struct SoundSettings {
  double sample_rate = 48000;  ///< Hz, 8000 .. 192000
  /// A strike sounds only if the parts approached at least this fast, m/s.
  /// Resting contacts that flicker on and off approach at mm/s and stay silent.
  double min_speed = 0.1;
  /// ... and with at least this contact impulse, N*s (0: no impulse needed).
  double min_impulse = 0;
  double gain = 1;               ///< master gain applied to every strike
  std::int64_t max_voices = 32;  ///< voices ringing at once; more replace the quietest

  /// Reads and checks the plugin settings (InputError names the bad key).
  static SoundSettings from(const PluginSettings& settings);
};

/// One strike, as an interaction queues it.
struct Strike {
  ObjectId part;            ///< the part that rings (must carry `acoustic`)
  ObjectId other;           ///< what struck it, if known (for the event)
  double normal_speed = 0;  ///< speed of approach along the contact normal, m/s
  double impulse = 0;       ///< contact impulse, N*s (0: unknown)
};

/// Fundamental amplitude (full scale = 1) per m/s of strike velocity at
/// loudness 1: a 1 m/s strike starts at -14 dBFS, a 5 m/s one at full scale.
inline constexpr double kAmplitudePerSpeed = 0.2;
/// Bounds on a mode's T60, s: a zero decay would be a click of no length, a
/// zero loss factor a voice that never ends.
inline constexpr double kMinDecay = 1e-3, kMaxDecay = 60;

class SoundResolver : public Resolver {
 public:
  /// `start_time`: world time at creation, s (the time of the first sample).
  SoundResolver(SoundSettings settings, double start_time);

  // --- interaction function -------------------------------------------------
  /// Queues a strike; performed at the start of the next advance.
  void strike(const Strike& s) { queue_.push_back(s); }

  // --- Resolver ---------------------------------------------------------------
  void build(ResolverAccess& access) override {}
  void advance(ResolverAccess& access, double dt) override;
  /// Saves the voices in flight and the sample clock (docs/saves.md).
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;

  // --- for apps: what the run sounded like ------------------------------------
  /// Mono samples since the resolver started (or since the last take_samples),
  /// full scale = 1. A loud run may exceed 1: the buffer is not clipped.
  std::span<const float> samples() const { return samples_; }
  /// Hands over the buffered samples and empties the buffer (a viewer that
  /// streams audio calls this each frame; `alloy run --audio` uses samples()).
  std::vector<float> take_samples();
  double sample_rate() const { return settings_.sample_rate; }
  /// World time of the first sample ever produced, s.
  double start_time() const { return start_time_; }
  /// Samples produced since the start (taken or not).
  std::uint64_t samples_produced() const { return produced_; }
  std::size_t voice_count() const { return synth_.voice_count(); }
  const SoundSettings& settings() const { return settings_; }
  /// True if a strike of this speed and impulse would sound (the thresholds).
  bool audible(double normal_speed, double impulse) const {
    return normal_speed >= settings_.min_speed && impulse >= settings_.min_impulse;
  }

  /// What a part sounds like when struck (pitch, decay): the fall-back chain
  /// of acoustic_model.hpp applied to the part's properties. For tests, the
  /// viewer and docs; advance() uses the same function.
  struct Voicing {
    Family family = Family::bar;
    double pitch = 0;  ///< fundamental, Hz
    double decay = 0;  ///< T60 of the fundamental, s
    double loudness = 1;
  };
  static Voicing voicing(const WorldView& world, ObjectId part);

 private:
  void perform(ResolverAccess& access, const Strike& s);

  SoundSettings settings_;
  ModalSynth synth_;
  std::vector<Strike> queue_;
  std::vector<float> samples_;
  double start_time_ = 0;
  double elapsed_ = 0;          // simulated time advanced, s
  std::uint64_t produced_ = 0;  // samples produced, = round(elapsed_ * rate)
};

/// Registers the `sound` resolver and its property types.
void register_sound_resolver(PluginRegistry& registry);

}  // namespace alloy::sound
