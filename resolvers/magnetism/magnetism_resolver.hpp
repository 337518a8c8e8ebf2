// The magnetism resolver (paper 4.1.3.1: "the magnetics resolver has one
// magnet to activate"). Its only state is the pole strength of each
// electromagnet, kept in the `pole_strength` property; the heavy work (fields,
// induced poles, forces) is the `magnetic_forces` derived set.
//
// Contract:
//   reads    magnet, turns, coil_factor, coil_time_constant, pole_separation and
//            the shape (for the default coil factor)
//   writes   pole_strength, and only for electromagnets that received a command
//   queue    set_coil_current(), called by interactions (magnetism_from_electricity)
//            in the interact phase; performed at the start of the next advance
//   events   "electromagnet_on" / "electromagnet_off" when a coil's commanded
//            current becomes non-zero / zero (values: current A, pole_strength A*m
//            the coil is heading for)
//
// An electromagnet that never received a command keeps whatever pole_strength
// the scene gave it (0 by default): it behaves as a permanent magnet until a
// circuit drives it. Once commanded it keeps the last commanded current until
// told otherwise, so commands need only be sent when the current changes
// (magnetism_from_electricity sends every step, which is also correct).
//
// Rates (setting `rates = true`, off by default): a command may carry the
// current's rate dI/dt as of the command's time (the start of the next
// advance). The pole strength is then set for the end of the advance, the
// current moved on by its rate (a first-order prediction over the window
// that the command waited), and every electromagnet publishes
// `pole_strength_rate` (A*m/s), which magnetic_forces with rates folds into
// the loads' rates. Without it a coil's magnet lags its current by a window
// (docs/performance.md "Multi-rate coupling").
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "resolvers/magnetism/magnet_parts.hpp"
#include "runtime/stage.hpp"
#include "runtime/stage_state.hpp"
#include "runtime/world.hpp"

namespace alloy::magnetism {

class MagnetismResolver : public Resolver {
 public:
  /// Plugin name.
  static constexpr const char* kName = "magnetism";

  // --- interaction functions (queue only) ------------------------------------
  /// From the next advance on, the coil of electromagnet `id` carries `current`
  /// amperes; its pole strength heads for coil_factor * turns * current, with
  /// the sign of the current. A command for an object that is not an
  /// electromagnet (or is gone by then), or with a non-finite current, is
  /// refused when performed and reported as a "magnetism_command_refused" event.
  void set_coil_current(ObjectId id, double current);
  /// The same with the current's rate, A/s (used with the setting `rates`;
  /// without it the rate is ignored).
  void set_coil_current(ObjectId id, double current, double rate);

  explicit MagnetismResolver(bool rates = false) : rates_(rates) {}
  bool rates() const { return rates_; }

  // --- Resolver ------------------------------------------------------------------
  void build(ResolverAccess& access) override;
  void advance(ResolverAccess& access, double dt) override;
  /// The coil records (each commanded coil's current and rate): a coil's
  /// "electromagnet_off" is published when a command turns an "on" record
  /// off, so a restored resolver without them would miss it. Not the queue:
  /// a restore primes the interactions, which queue the same commands again.
  /// Nothing (no state) while no coil was ever commanded.
  bool save_state(StateWriter& out) const override;
  void restore_state(StateReader& in) override;

  // --- inspection ----------------------------------------------------------------
  /// The current last commanded for electromagnet `id` (A), or nullopt if none yet.
  std::optional<double> commanded_current(ObjectId id) const;
  /// Commands waiting for the next advance.
  std::size_t queued() const { return queue_.size(); }

 private:
  struct Command {
    ObjectId id;
    double current = 0;
    double rate = 0;
  };
  /// Per slot: the coil's commanded current, valid while `id` is the live object.
  struct Coil {
    ObjectId id{};
    bool commanded = false;
    double current = 0;
    double rate = 0;
  };
  bool rates_ = false;
  std::vector<Command> queue_;
  std::vector<Coil> coils_;
  std::optional<MagnetColumns::Ids> ids_;  // resolved at the first build or advance
};

}  // namespace alloy::magnetism
