// The (Electricity <- Collisions) interaction of paper 4.1.2 and 4.1.4.3:
// conductive parts that touch are connected, and disconnected when they part.
//
// Reads    the `collisions` derived set (began, ongoing, ended pairs with their
//          contact points), conductive, position, orientation.
// Target   electricity: connect(a, b, terminal_a, terminal_b) / disconnect(a, b),
//          performed in its next advance (the one-step delay of paper 3.2).
//
// Level-triggered: each apply compares the touching pairs of both-conductive
// parts (began + ongoing) with the pairs it has already connected, and sends
// connect for the new ones and disconnect for those gone. In a normal run that
// is exactly "began -> connect, ended -> disconnect"; it also stays right
// when the collisions set is skipped (nothing moved, its lists unchanged),
// when a part stops being conductive while touching, and when it starts: the
// first apply connects every pair already touching (a battery dropped into a
// running world; a newly created electricity resolver recovers its contacts).
//
// Which terminal a touch reaches. A two-terminal part (battery, coil,
// resistor) has terminal 0 at its -x end and terminal 1 at its +x end, in its
// own frame; a touch connects to the terminal of the half it lands on (the mean
// of the pair's contact points, mapped into the part's frame). The terminal is
// chosen when the contact is made and kept while it lasts. For a single-node
// part the terminal does not matter.
//
// Contacts between steps (setting `ahead`, off by default; docs/electricity.md
// "Contacts between steps"). A touch that happens inside a step is seen at the
// step's end and connected for the step after: on average half a step late,
// always late. With `ahead = true` the interaction also asks the contact set
// which conductive parts would touch half a step on, were they to move on
// with their present velocities (ContactSet::touching_ahead), and connects
// those now: a make is then connected at the step boundary nearest to it,
// half a step early as often as half a step late. A predicted touch that the
// next update does not find (and does not predict again) is disconnected
// there. Breaks are not predicted: a resting contact's predicted separation is
// the size of its solver's penetration, too small to tell a break from rest.
#pragma once

#include <utility>
#include <vector>

#include "resolvers/electricity/electricity.hpp"
#include "runtime/contact_set.hpp"

namespace alloy::electricity {

class ElectricityFromCollisions final : public Interaction {
 public:
  /// The most updates a predicted pair waits for its contact set's report
  /// (ContactSet::report_lag, clamped to it; a saved count above it is damage).
  static constexpr int kMaxReportLag = 4;
  /// ahead: connect now a touch predicted within half a step (setting
  /// `ahead`, see the header).
  ElectricityFromCollisions(ElectricityResolver& target, const ContactSet& contacts,
                            bool ahead = false);
  void apply(const WorldView& world) override;
  /// The pairs connected before the last apply: a restore primes the
  /// interactions again, and this apply must then queue what the last one
  /// queued (docs/saves.md).
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;

  /// The terminal of a part that a touch at `point` (world frame, m) reaches:
  /// 1 if the point lies on the part's +x side of its centre, else 0.
  static int terminal_at(Vec3 part_position, Quat part_orientation, Vec3 point);

 private:
  ElectricityResolver& target_;
  const ContactSet& contacts_;
  bool ahead_ = false;
  std::vector<ObjectId> conductors_;  // scratch: the conductive placed parts (ahead_)
  /// Pairs connected by a prediction and not yet reported touching, with the
  /// updates they have waited (ahead_; see apply), sorted; and as before the
  /// last apply (saved, as before_ is).
  std::vector<std::pair<std::pair<ObjectId, ObjectId>, std::int32_t>> waiting_, waiting_before_;
  std::vector<std::pair<ObjectId, ObjectId>> connected_;  // pairs we connected, sorted (a < b)
  std::vector<std::pair<ObjectId, ObjectId>> before_;     // connected_ before the last apply
  PropertyRef conductive_{prop::kConductive}, position_{"position"}, orientation_{"orientation"};
};

/// Registers the `electricity_from_collisions` interaction (register_electricity_plugins
/// does). Needs the rigid body's plugins (the `collisions` set) registered for the
/// interaction to be instantiated.
void register_electricity_from_collisions(PluginRegistry& registry);

}  // namespace alloy::electricity
