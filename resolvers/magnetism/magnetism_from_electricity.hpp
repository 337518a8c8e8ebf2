// The (Magnetism <- Electricity) interaction of paper 4.1.2.2: a coil in a
// closed circuit becomes a magnet. Each step it reads the `current` the
// electricity resolver published for every electromagnet and queues it on the
// magnetism resolver, which sets the coil's pole strength in its next advance
// (the one-step delay of paper 3.2: a current of step n magnetises at step n+1).
//
// Contract:
//   reads    magnet, current (A, signed; written by electricity)
//   target   magnetism (set_coil_current)
//   needs    magnet, and the `electricity` resolver active (declared in
//            StageInfo::resolvers): then it runs from the first step, so even
//            the first current arrives one step late, not two. An electromagnet
//            that carries no current (not wired) is commanded 0 A.
#pragma once

#include "resolvers/magnetism/magnet_parts.hpp"
#include "resolvers/magnetism/magnetism_resolver.hpp"
#include "runtime/property_ref.hpp"
#include "runtime/stage.hpp"

namespace alloy::magnetism {

class MagnetismFromElectricity : public Interaction {
 public:
  /// Plugin name.
  static constexpr const char* kName = "magnetism_from_electricity";

  /// `induction_order`: electricity's setting of that name (1 or 2), which
  /// sets the current's lead (1.5 or 1 step; docs/magnetism.md). 2 is
  /// electricity's default (electricity::kDefaultInductionOrder).
  explicit MagnetismFromElectricity(MagnetismResolver& target, int induction_order = 2)
      : target_(target), induction_order_(induction_order) {}
  void apply(const WorldView& world) override;

 private:
  MagnetismResolver& target_;
  int induction_order_ = 2;
  PropertyRef magnet_{prop::kMagnet}, current_{prop::kCurrent};
};

}  // namespace alloy::magnetism
