// sound_from_collisions (paper 4.1.6.2, "Sound <- Collisions"): parts that hit
// each other ring. Reads the rigid body's `collisions` derived set and queues
// strikes on the `sound` resolver; both parts of a pair ring if both carry
// `acoustic`.
//
// When. A pair that began touching is an impact if it closed in at least at
// the sound resolver's min_speed. Its impulse is not known yet at that moment:
// the rigid body resolves a contact in the advance after the collisions set
// reported it, and the set publishes that impulse at its next update (the
// pair is then ongoing, or ended if it bounced apart within one step). So an
// impact waits one update and is struck with the impulse the rigid body
// actually applied, which is what makes a light striker ring a heavy bell
// softly. The ding thus starts two steps after the touch (8 ms at 240 Hz),
// below what a listener hears as late. A pair that shows no impulse by then
// (two immovable parts) is struck with its speed alone.
//
// Each impact rings once: pairs are remembered by (a, b, began_step) while
// they touch, so a collisions set that was skipped (nothing moved) and still
// lists the same began pairs does not strike them again.
#pragma once

#include <cstdint>
#include <vector>

#include "resolvers/sound/sound_resolver.hpp"
#include "runtime/contact_set.hpp"
#include "runtime/property_ref.hpp"

namespace alloy::sound {

class SoundFromCollisions final : public Interaction {
 public:
  SoundFromCollisions(SoundResolver& sound, const ContactSet& collisions)
      : sound_(sound), collisions_(collisions), impulses_(collisions.demand_impulses()) {}

  void apply(const WorldView& world) override;

  /// The impacts waiting and the pairs already handled, as they were before
  /// the last apply: a restore primes interactions by applying them once, and
  /// that apply repeats the last one (the same strikes queued, the same
  /// impacts left waiting), as the collisions set repeats its last update.
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;

  /// Impacts waiting for their impulse (for tests).
  std::size_t pending() const { return pending_.size(); }

 private:
  struct Key {
    ObjectId a, b;
    std::uint64_t began_step = 0;
    friend auto operator<=>(const Key&, const Key&) = default;
  };
  struct Impact {
    Key key;
    double normal_speed = 0;
  };

  void strike(const WorldView& world, const Impact& impact, double impulse);

  PropertyRef acoustic_{"acoustic"};

  SoundResolver& sound_;
  const ContactSet& collisions_;
  ImpulseDemand impulses_;       // strikes are as hard as the impulse: declared to the rigid body
  std::vector<Impact> pending_;  // began at the last apply, struck at this one
  std::vector<Key> seen_;        // began pairs already handled, sorted; pruned when they end
  std::vector<Impact> pending_before_;  // pending_ and seen_ before the last apply (save_state)
  std::vector<Key> seen_before_;
};

/// Registers `sound_from_collisions` (needs the `sound` resolver and the
/// `collisions` set to be registered too).
void register_sound_from_collisions(PluginRegistry& registry);

}  // namespace alloy::sound
