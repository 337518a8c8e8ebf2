#include "resolvers/sound/sound_from_collisions.hpp"

#include <algorithm>

namespace alloy::sound {

void SoundFromCollisions::apply(const WorldView& world) {
  // 1. Impacts that began at the last apply: the rigid body has resolved them
  //    since, and the collisions set carries the impulse it applied.
  for (const Impact& impact : pending_) {
    const Key& k = impact.key;
    double impulse = 0;
    if (const ContactPair* p = collisions_.find(k.a, k.b);
        p && p->began_step == k.began_step) {
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

void register_sound_from_collisions(PluginRegistry& registry) {
  registry.add({
      .info = {.name = "sound_from_collisions",
               .kind = StageKind::Interaction,
               .reads = {"acoustic"},
               .derived = {"collisions"},
               .target = "sound",
               .doc = "parts that hit each other ring, as hard as the rigid body's impulse says"},
      .create = [](PluginContext& ctx) -> std::unique_ptr<Stage> {
        return std::make_unique<SoundFromCollisions>(
            ctx.target<SoundResolver>(), ctx.dependency<ContactSet>("collisions"));
      },
  });
}

}  // namespace alloy::sound
