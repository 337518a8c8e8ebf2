#include "resolvers/sound/sound_resolver.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace alloy::sound {

namespace {

PropertyDef number(const char* name, const char* unit, const char* doc, std::optional<double> min) {
  return {.name = name, .kind = PropertyKind::Number, .unit = unit, .doc = doc, .min = min};
}

/// A property's value if the property is registered and the part carries it.
template <class T>
std::optional<T> read(const WorldView& w, std::string_view name, ObjectId part) {
  const auto id = w.properties().find(name);
  if (!id) return std::nullopt;
  const ColumnView<T> c = w.column<T>(*id);
  if (!c.has(part)) return std::nullopt;
  return c[part.index];
}

/// The dimensions the pitch formulas need, from the rigid body's shape.
struct Dimensions {
  double length = 0;     // bar: the free length, m
  double gyration = 0;   // bar: radius of gyration of the cross-section, m
  double radius = 0;     // bell: radius of the mouth, m
  double thickness = 0;  // bell: wall thickness, m
  double volume = 0;     // m^3 (for density = mass / volume)
};

std::optional<Dimensions> dimensions(const WorldView& w, ObjectId part) {
  // The rigid body's shape properties, read by name and enum value name: the
  // property names are the contract between resolvers, not each other's code.
  const auto shape_id = w.properties().find("shape");
  const auto shape = read<EnumValue>(w, "shape", part);
  if (!shape_id || !shape) return std::nullopt;
  const auto& names = w.properties().def(*shape_id).enum_values;
  if (shape->index < 0 || std::size_t(shape->index) >= names.size()) return std::nullopt;
  const std::string& kind = names[std::size_t(shape->index)];
  constexpr double pi = std::numbers::pi;
  Dimensions d;
  if (kind == "box") {
    const auto size = read<Vec3>(w, "size", part);
    if (!size) return std::nullopt;
    std::array<double, 3> e = {size->x, size->y, size->z};
    std::sort(e.begin(), e.end());
    // The lowest bending mode bends the bar across its thinnest side.
    d.length = e[2];
    d.gyration = e[0] / std::sqrt(12.0);
    d.radius = e[2] / 2;
    d.thickness = e[0];
    d.volume = e[0] * e[1] * e[2];
  } else if (kind == "sphere" || kind == "capsule") {
    const auto r = read<double>(w, "radius", part);
    if (!r) return std::nullopt;
    const double cyl = kind == "capsule" ? read<double>(w, "length", part).value_or(0) : 0;
    d.length = cyl + 2 * *r;
    d.gyration = *r / 2;  // solid round section: sqrt(I / A) = r / 2
    d.radius = *r;
    // Founders' rule of thumb: the sound bow is about 1/13 of the diameter thick.
    d.thickness = 2 * *r / 13;
    d.volume = pi * *r * *r * cyl + 4.0 / 3.0 * pi * *r * *r * *r;
  } else {
    return std::nullopt;
  }
  if (!(d.length > 0) || !(d.gyration > 0) || !(d.volume > 0)) return std::nullopt;
  return d;
}

}  // namespace

std::vector<PropertyDef> sound_properties() {
  return {
      {.name = "acoustic",
       .kind = PropertyKind::Enum,
       .doc = "the part rings when struck, as a bell (bell partials), a bar (free-free bending "
              "modes) or a block (a short clack); absent: silent",
       .enum_values = family_names()},
      number("pitch", "Hz",
             "fundamental when struck (a bell's prime); absent: from youngs_modulus, density "
             "and size, else the family's default",
             1.0),
      number("decay", "s",
             "time for the fundamental to fall 60 dB (T60); absent: from loss_factor, else the "
             "family's default",
             0.0),
      number("loss_factor", "",
             "material damping eta: T60 = ln(1000) / (pi f eta); e.g. bell bronze 1e-4, "
             "steel 5e-4, wood 1e-2",
             0.0),
      number("loudness", "", "gain of the part's sound (default 1)", 0.0),
      number("youngs_modulus", "Pa", "stiffness of the material, e.g. steel 2.0e11, wood 1.0e10",
             0.0),
      // The rigid body registers `density` too: the definition must be the same.
      {.name = "density",
       .kind = PropertyKind::Number,
       .unit = "kg/m^3",
       .doc = "density; when given, mass = density * volume of the shape",
       .min = 0.0,
       .min_exclusive = true},
  };
}

SoundSettings SoundSettings::from(const PluginSettings& p) {
  p.check_known("sound", {"sample_rate", "min_speed", "min_impulse", "gain", "max_voices"});
  SoundSettings s;
  s.sample_rate = p.number("sample_rate", s.sample_rate);
  s.min_speed = p.number("min_speed", s.min_speed);
  s.min_impulse = p.number("min_impulse", s.min_impulse);
  s.gain = p.number("gain", s.gain);
  s.max_voices = p.integer("max_voices", s.max_voices);
  auto bad = [&](const std::string& what) { throw InputError(p.where, "sound: " + what); };
  if (!(s.sample_rate >= 8000 && s.sample_rate <= 192000))
    bad("sample_rate must be between 8000 and 192000 Hz");
  if (s.sample_rate != std::floor(s.sample_rate)) bad("sample_rate must be a whole number of Hz");
  if (!(s.min_speed >= 0)) bad("min_speed must be >= 0 m/s");
  if (!(s.min_impulse >= 0)) bad("min_impulse must be >= 0 N*s");
  if (!(s.gain >= 0) || !std::isfinite(s.gain)) bad("gain must be a finite number >= 0");
  if (s.max_voices < 1) bad("max_voices must be at least 1");
  return s;
}

SoundResolver::SoundResolver(SoundSettings settings, double start_time)
    : settings_(settings),
      synth_(ModalSynth::Settings{.sample_rate = settings.sample_rate,
                                  .max_voices = std::size_t(settings.max_voices)}),
      start_time_(start_time) {}

SoundResolver::Voicing SoundResolver::voicing(const WorldView& w, ObjectId part) {
  Voicing v;
  v.family = Family(w.column<EnumValue>("acoustic").get(part).index);
  v.loudness = read<double>(w, "loudness", part).value_or(1.0);

  if (auto pitch = read<double>(w, "pitch", part)) {
    v.pitch = *pitch;
  } else {
    const auto stiffness = read<double>(w, "youngs_modulus", part);
    const auto dims = dimensions(w, part);
    std::optional<double> density = read<double>(w, "density", part);
    if (!density && dims)
      if (auto mass = read<double>(w, "mass", part)) density = *mass / dims->volume;
    if (stiffness && *stiffness > 0 && density && *density > 0 && dims) {
      v.pitch = v.family == Family::bell
                    ? plate_pitch(*stiffness, *density, dims->radius, dims->thickness)
                    : bar_pitch(*stiffness, *density, dims->length, dims->gyration);
    } else {
      v.pitch = default_pitch(v.family);
    }
  }

  if (auto decay = read<double>(w, "decay", part)) {
    v.decay = *decay;
  } else if (auto eta = read<double>(w, "loss_factor", part); eta && *eta > 0) {
    v.decay = decay_from_loss_factor(v.pitch, *eta);
  } else if (eta) {
    v.decay = kMaxDecay;  // no damping at all: ring as long as we allow
  } else {
    v.decay = default_decay(v.family);
  }
  v.decay = std::clamp(v.decay, kMinDecay, kMaxDecay);
  return v;
}

void SoundResolver::perform(ResolverAccess& access, const Strike& s) {
  // A strike queued last step may name a part destroyed or silenced since.
  if (!access.store().alive(s.part)) return;
  if (!access.column<EnumValue>("acoustic").has(s.part)) return;
  if (!std::isfinite(s.normal_speed) || !std::isfinite(s.impulse)) return;
  if (!audible(s.normal_speed, s.impulse)) return;

  const Voicing v = voicing(access, s.part);
  // What makes a body ring is the velocity the blow gives its surface: the
  // impulse over its mass. A light striker barely stirs a heavy bell; a part
  // without a mass (static scenery) or a strike without an impulse falls back
  // to the speed of approach, the most the surface can be given.
  double speed = s.normal_speed;
  if (s.impulse > 0)
    if (auto mass = read<double>(access, "mass", s.part); mass && *mass > 0)
      speed = std::min(s.impulse / *mass, 2 * s.normal_speed);
  const double amplitude = settings_.gain * v.loudness * kAmplitudePerSpeed * speed;

  const std::vector<Mode> modes = modes_of(v.family, v.pitch, v.decay, amplitude);
  synth_.strike(modes);

  Event e;
  e.type = "sound";
  e.a = s.part;
  e.b = s.other;
  e.values = {{"pitch", v.pitch}, {"amplitude", amplitude}, {"speed", speed}, {"decay", v.decay}};
  e.text = family_names()[std::size_t(v.family)];
  access.emit(std::move(e));
}

void SoundResolver::advance(ResolverAccess& access, double dt) {
  for (const Strike& s : queue_) perform(access, s);
  queue_.clear();

  // Exactly the samples that cover [elapsed, elapsed + dt): rounding the
  // running total (not each step's share) keeps the buffer within half a
  // sample of the simulated time over any number of steps.
  elapsed_ += dt;
  const auto target = std::uint64_t(std::llround(elapsed_ * settings_.sample_rate));
  if (target <= produced_) return;
  const std::size_t n = std::size_t(target - produced_);
  const std::size_t at = samples_.size();
  samples_.resize(at + n, 0.0f);
  synth_.render(std::span<float>(samples_).subspan(at, n));
  produced_ = target;
}

std::vector<float> SoundResolver::take_samples() {
  std::vector<float> out;
  out.swap(samples_);
  return out;
}

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------

namespace {
constexpr std::uint32_t kStateVersion = 1;
}

bool SoundResolver::save_state(StateWriter& out) const {
  // The voices ring on across the restore, and the clock keeps rounding the
  // running total: a fresh clock would round each step's share anew and give
  // a sample more or less here and there. The start time and the count keep
  // samples_produced() and start_time() those of the uninterrupted run (the
  // buffer itself is output, not state: after a restore it holds what was
  // produced since). The strikes queued are not saved: a restore primes the
  // interactions, which queue them again (sound_from_collisions saves its
  // pending impacts as they were before its last apply, for that).
  out.put(kStateVersion);
  out.put(start_time_);
  out.put(elapsed_);
  out.put(produced_);
  out.put_vector(synth_.voices_state());
  return true;
}

void SoundResolver::restore_state(StateReader& in) {
  if (const auto v = in.get<std::uint32_t>(); v != kStateVersion)
    throw InputError("the saved state of stage '" + in.stage() + "' is of version " +
                     std::to_string(v) + ", this build reads " + std::to_string(kStateVersion));
  const double start = in.get<double>(), elapsed = in.get<double>();
  const auto produced = in.get<std::uint64_t>();
  const std::vector<double> voices = in.get_vector<double>();
  if (!std::isfinite(start) || !std::isfinite(elapsed) || elapsed < 0 ||
      produced != std::uint64_t(std::llround(elapsed * settings_.sample_rate)))
    throw InputError("the saved state of stage '" + in.stage() +
                     "' has a sample clock that does not add up (" + std::to_string(produced) +
                     " samples in " + std::to_string(elapsed) + " s)");
  if (!synth_.set_voices_state(voices))
    throw InputError("the saved state of stage '" + in.stage() +
                     "' holds voices that are damaged or more than " +
                     std::to_string(synth_.settings().max_voices) + " (its max_voices)");
  start_time_ = start, elapsed_ = elapsed, produced_ = produced;
}

void register_sound_resolver(PluginRegistry& registry) {
  registry.add({
      .info = {.name = "sound",
               .kind = StageKind::Resolver,
               .reads = {"acoustic", "pitch", "decay", "loss_factor", "loudness", "youngs_modulus",
                         "density"},
               .needs = {"acoustic"},
               .doc = "struck parts ring (modal synthesis); the run's audio, in step with the "
                      "simulation"},
      .properties = sound_properties(),
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        return std::make_unique<SoundResolver>(SoundSettings::from(ctx.settings()),
                                               ctx.world().time());
      },
  });
}

}  // namespace alloy::sound
