#include "resolvers/sound/sound_from_collisions.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace alloy::sound {

void SoundFromCollisions::apply(const WorldView& world) {
  pending_before_ = pending_, seen_before_ = seen_;  // a few pairs: the copy is cheap
  // 1. Impacts that began at the last apply: the rigid body has resolved them
  //    since, and the collisions set carries the impulse it applied.
  for (const Impact& impact : pending_) {
    const Key& k = impact.key;
    double impulse = 0;
    if (const ContactPair* p = collisions_.find(k.a, k.b); p && p->began_step == k.began_step) {
      impulse = p->total_impulse;
    } else {
      for (const ContactPair& e : collisions_.ended())
        if (e.a == k.a && e.b == k.b && e.began_step == k.began_step) impulse = e.total_impulse;
    }
    strike(world, impact, impulse);
  }
  pending_.clear();

  // 2. Forget pairs that no longer touch: they may begin again, and ring again.
  std::erase_if(seen_, [&](const Key& k) {
    const ContactPair* p = collisions_.find(k.a, k.b);
    return !p || p->began_step != k.began_step;
  });

  // 3. New impacts (began is sorted by pair, so pending_ is in a fixed order).
  const auto acoustic = acoustic_.column<EnumValue>(world);
  const double min_speed = sound_.settings().min_speed;
  for (const ContactPair& p : collisions_.began()) {
    const Key k{p.a, p.b, p.began_step};
    auto at = std::lower_bound(seen_.begin(), seen_.end(), k);
    if (at != seen_.end() && *at == k) continue;  // already handled (the set was skipped)
    seen_.insert(at, k);
    if (!acoustic.has(p.a) && !acoustic.has(p.b)) continue;
    if (!(p.normal_speed >= min_speed)) continue;  // a touch, not a blow
    pending_.push_back({k, p.normal_speed});
  }
}

void SoundFromCollisions::strike(const WorldView& world, const Impact& impact, double impulse) {
  const auto acoustic = acoustic_.column<EnumValue>(world);
  const ObjectId a = impact.key.a, b = impact.key.b;
  if (acoustic.has(a))
    sound_.strike({.part = a, .other = b, .normal_speed = impact.normal_speed, .impulse = impulse});
  if (acoustic.has(b))
    sound_.strike({.part = b, .other = a, .normal_speed = impact.normal_speed, .impulse = impulse});
}

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------

namespace {
constexpr std::uint32_t kStateVersion = 1;
}

bool SoundFromCollisions::save_state(StateWriter& out) const {
  out.put(kStateVersion);
  out.put_vector(pending_before_);
  out.put_vector(seen_before_);
  return true;
}

void SoundFromCollisions::restore_state(StateReader& in) {
  if (const auto v = in.get<std::uint32_t>(); v != kStateVersion)
    throw InputError("the saved state of stage '" + in.stage() + "' is of version " +
                     std::to_string(v) + ", this build reads " + std::to_string(kStateVersion));
  auto pending = in.get_vector<Impact>();
  auto seen = in.get_vector<Key>();
  // seen_ is searched by binary search: it must be sorted and distinct.
  for (std::size_t i = 1; i < seen.size(); ++i)
    if (!(seen[i - 1] < seen[i]))
      throw InputError("the saved state of stage '" + in.stage() +
                       "' is damaged: its handled pairs are out of order");
  for (const Impact& p : pending)
    if (!(p.normal_speed >= 0) || !std::isfinite(p.normal_speed))
      throw InputError("the saved state of stage '" + in.stage() +
                       "' is damaged: an impact speed of " + std::to_string(p.normal_speed));
  pending_ = pending_before_ = std::move(pending);
  seen_ = seen_before_ = std::move(seen);
}

void register_sound_from_collisions(PluginRegistry& registry) {
  registry.add({
      .info = {.name = "sound_from_collisions",
               .kind = StageKind::Interaction,
               .reads = {"acoustic"},
               .derived = {"collisions"},
               .target = "sound",
               .doc = "parts that hit each other ring, as hard as the rigid body's impulse says"},
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        return std::make_unique<SoundFromCollisions>(ctx.target<SoundResolver>(),
                                                     ctx.dependency<ContactSet>("collisions"));
      },
  });
}

}  // namespace alloy::sound
