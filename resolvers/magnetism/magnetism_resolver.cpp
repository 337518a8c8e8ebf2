#include "resolvers/magnetism/magnetism_resolver.hpp"

#include <cmath>
#include <string>

#include "resolvers/magnetism/magnet_parts.hpp"

namespace alloy::magnetism {

void MagnetismResolver::set_coil_current(ObjectId id, double current) {
  queue_.push_back({id, current, 0.0});
}

void MagnetismResolver::set_coil_current(ObjectId id, double current, double rate) {
  queue_.push_back({id, current, std::isfinite(rate) ? rate : 0.0});
}

std::optional<double> MagnetismResolver::commanded_current(ObjectId id) const {
  if (id.index >= coils_.size()) return std::nullopt;
  const Coil& c = coils_[id.index];
  if (c.id != id || !c.commanded) return std::nullopt;
  return c.current;
}

void MagnetismResolver::build(ResolverAccess& access) {
  if (!ids_) ids_ = MagnetColumns::Ids::resolve(access);
  const MagnetColumns c = MagnetColumns::bind(access, *ids_);
  const PropertyStore& store = access.store();
  // Refuse a part that cannot be simulated now, naming it, rather than letting
  // it exert nothing without a word.
  for (std::uint32_t slot : c.magnet.members()) {
    if (std::string why = check_part(c, slot); !why.empty())
      throw InputError(ErrorLocation{.object = store.describe(store.id_at(slot))}, why);
  }
  // With rates every electromagnet carries its rate from the start, so that
  // advance() changes values only (a new member would be a structural change).
  if (rates_) {
    auto rate = access.writer<double>(prop::kPoleStrengthRate);
    for (std::uint32_t slot : c.magnet.members())
      if (c.kind(slot) == MagnetKind::Electromagnet && !rate.has(slot)) rate.set(slot, 0.0);
  }
  // Commanded currents survive a rebuild for the coils that are still coils.
  coils_.resize(store.slot_count());
  for (std::uint32_t slot = 0; slot < coils_.size(); ++slot) {
    Coil& coil = coils_[slot];
    if (coil.id.is_null()) continue;
    if (!store.alive(coil.id) || !c.magnet.has(slot) || c.kind(slot) != MagnetKind::Electromagnet)
      coil = Coil{};
  }
}

void MagnetismResolver::advance(ResolverAccess& access, double dt) {
  if (!ids_) ids_ = MagnetColumns::Ids::resolve(access);
  const MagnetColumns c = MagnetColumns::bind(access, *ids_);
  const PropertyStore& store = access.store();
  auto pole_strength = access.writer<double>(ids_->pole_strength);
  std::optional<ColumnWriter<double>> pole_rate;
  if (rates_) pole_rate.emplace(access.writer<double>(prop::kPoleStrengthRate));

  // 1. Perform the commands queued by the interactions of the last step.
  for (const Command& cmd : queue_) {
    const char* refused = nullptr;
    if (!store.alive(cmd.id))
      refused = "the object no longer exists";
    else if (!c.magnet.has(cmd.id.index) || c.kind(cmd.id.index) != MagnetKind::Electromagnet)
      refused = "the object is not an electromagnet";
    else if (!std::isfinite(cmd.current))
      refused = "the current is not a finite number";
    if (refused) {
      access.emit({.type = "magnetism_command_refused",
                   .a = cmd.id,
                   .values = {{"current", cmd.current}},
                   .text = std::string("set_coil_current: ") + refused});
      continue;
    }
    if (coils_.size() <= cmd.id.index) coils_.resize(cmd.id.index + 1);
    Coil& coil = coils_[cmd.id.index];
    if (coil.id != cmd.id) coil = Coil{.id = cmd.id};
    const bool was_on = coil.commanded && coil.current != 0;
    const bool now_on = cmd.current != 0;
    coil.commanded = true;
    coil.current = cmd.current;
    coil.rate = cmd.rate;
    if (was_on != now_on) {
      const double target = coil_factor(c, cmd.id.index).value_or(0) *
                            c.turns.value_or(cmd.id.index, 0.0) * cmd.current;
      access.emit({.type = now_on ? "electromagnet_on" : "electromagnet_off",
                   .a = cmd.id,
                   .values = {{"current", cmd.current}, {"pole_strength", target}}});
    }
  }
  queue_.clear();

  // 2. Move each commanded coil's pole strength toward coil_factor * N * I.
  for (std::uint32_t slot : c.magnet.members()) {
    if (slot >= coils_.size() || c.kind(slot) != MagnetKind::Electromagnet) continue;
    const Coil& coil = coils_[slot];
    if (!coil.commanded || coil.id != store.id_at(slot)) continue;
    const double per_ampere = coil_factor(c, slot).value_or(0) * c.turns.value_or(slot, 0.0);
    // With rates the command's current is as of the advance's start: the
    // pole strength is set for its end, the current moved on by its rate.
    const double current = rates_ ? coil.current + coil.rate * dt : coil.current;
    const double target = per_ampere * current;
    const double tau = c.coil_time_constant.value_or(slot, 0.0);
    const double present = pole_strength.has(slot) ? pole_strength[slot] : 0.0;
    double next = target;
    if (tau > 0) {
      // Exact solution of dq/dt = (target - q) / tau over the step: the paper's
      // "rapidly (but not instantly)" cool-down, stable for any dt.
      next = present + (target - present) * -std::expm1(-dt / tau);
      // Land exactly on the target once the rest is rounding, so that a coil
      // at rest stops changing the column (and stops waking the forces).
      if (std::abs(next - target) <= 1e-9 * std::abs(target) + 1e-12) next = target;
    }
    pole_strength.set(slot, next);
    // dq/dt at the end: the target's own rate, or with a time constant the
    // relaxation toward the (moving) target.
    if (pole_rate) pole_rate->set(slot, tau > 0 ? (target - next) / tau : per_ampere * coil.rate);
  }
}

// --- save and restore (Stage::save_state; docs/saves.md) ------------------------------
//
// The bytes: a version, then the commanded coils (slot, id, current, rate),
// in slot order. The rate matters with `rates` only, but is saved always so
// that the bytes do not depend on a setting.

namespace {
constexpr std::uint32_t kStateVersion = 1;
struct SavedCoil {
  ObjectId id;
  double current, rate;
};
static_assert(sizeof(SavedCoil) == 24, "no padding: a padding byte would be arbitrary");
}  // namespace

bool MagnetismResolver::save_state(StateWriter& out) const {
  std::vector<SavedCoil> coils;
  for (const Coil& c : coils_)
    if (!c.id.is_null() && c.commanded) coils.push_back({c.id, c.current, c.rate});
  if (coils.empty()) return false;
  out.put(kStateVersion);
  out.put_vector(coils);
  return true;
}

void MagnetismResolver::restore_state(StateReader& in) {
  auto fail = [&](const std::string& why) {
    throw InputError("the saved state of stage '" + in.stage() + "' is damaged: " + why);
  };
  if (const auto v = in.get<std::uint32_t>(); v != kStateVersion)
    fail("state version " + std::to_string(v) + ", this build reads " +
         std::to_string(kStateVersion));
  const std::vector<SavedCoil> coils = in.get_vector<SavedCoil>();
  // build() ran on the restored properties: coils_ covers every slot, and a
  // record must name a live electromagnet, in slot order, once.
  std::uint32_t next = 0;
  for (const SavedCoil& s : coils) {
    if (s.id.is_null() || s.id.index >= coils_.size() || s.id.index < next)
      fail("a coil record names slot " + std::to_string(s.id.index) + " out of order or range");
    if (!std::isfinite(s.current) || !std::isfinite(s.rate))
      fail("coil #" + std::to_string(s.id.index) + " has a current that is not a finite number");
    coils_[s.id.index] = Coil{.id = s.id, .commanded = true, .current = s.current, .rate = s.rate};
    next = s.id.index + 1;
  }
}

}  // namespace alloy::magnetism
