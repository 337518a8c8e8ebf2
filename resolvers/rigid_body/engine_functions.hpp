// The rigid body's interaction functions as data (runtime/interaction_function.hpp),
// for any RigidBodyEngine: every engine that provides `rigid_body` puts these
// in its PluginDef, so that Lua mods and native interactions call ODE and
// other engines alike, and the registry's check that providers declare the
// same functions holds by construction:
//
//   def.functions = rigid::engine_functions();
//   def.records = rigid::engine_records();
//
//   add_force(vec3)           force at the centre of mass, N
//   add_torque(vec3)          torque, N m, world frame
//   add_force_at(vec3, vec3)  force at the world point (second vec3), N
//
// The callables cast the stage they are given to RigidBodyEngine: bindings
// pass only the stage the declaring plugin created, which is one.
#pragma once

#include <cstddef>
#include <type_traits>
#include <vector>

#include "resolvers/rigid_body/engine.hpp"
#include "runtime/interaction_function.hpp"
#include "runtime/property_store.hpp"

namespace alloy::rigid {

// The engine's queue entry is written in place as the runtime's LoadRecord:
// the same bytes.
static_assert(sizeof(RigidBodyEngine::LoadCommand) == sizeof(LoadRecord) &&
              offsetof(RigidBodyEngine::LoadCommand, slot) == offsetof(LoadRecord, slot) &&
              offsetof(RigidBodyEngine::LoadCommand, generation) ==
                  offsetof(LoadRecord, generation) &&
              offsetof(RigidBodyEngine::LoadCommand, value) == offsetof(LoadRecord, value) &&
              offsetof(RigidBodyEngine::LoadCommand, point) == offsetof(LoadRecord, point) &&
              offsetof(RigidBodyEngine::LoadCommand, kind) == offsetof(LoadRecord, kind) &&
              sizeof(RigidBodyEngine::Load) == sizeof(LoadRecord::kind) &&
              std::is_trivially_copyable_v<RigidBodyEngine::LoadCommand>);

inline std::vector<InteractionFunction> engine_functions() {
  using Load = RigidBodyEngine::Load;
  auto engine = [](Stage& s) -> RigidBodyEngine& { return static_cast<RigidBodyEngine&>(s); };
  auto v = [](const double* a) { return Vec3{a[0], a[1], a[2]}; };
  std::vector<InteractionFunction> fns(3);

  fns[0].decl = {"add_force", {ArgKind::Vec3}};
  fns[0].doc = "force at the centre of mass, N";
  fns[0].call = [=](Stage& s, ObjectId id, const double* a) { engine(s).add_force(id, v(a)); };
  fns[0].call_live = [=](Stage& s, std::uint32_t slot, const double* a) {
    engine(s).add_force(slot, v(a));
  };
  fns[0].each = [=](Stage& s, std::span<const std::uint32_t> members, const std::uint8_t* present,
                    const double* values, const PropertyStore&) {
    RigidBodyEngine& e = engine(s);
    for (std::uint32_t m : members)
      if (present[m] == 1) e.add_force(m, v(values + 3 * std::size_t(m)));
  };
  fns[0].record_kind = int(Load::Force);

  fns[1].decl = {"add_torque", {ArgKind::Vec3}};
  fns[1].doc = "torque, N m, world frame";
  fns[1].call = [=](Stage& s, ObjectId id, const double* a) { engine(s).add_torque(id, v(a)); };
  fns[1].each = [=](Stage& s, std::span<const std::uint32_t> members, const std::uint8_t* present,
                    const double* values, const PropertyStore& store) {
    RigidBodyEngine& e = engine(s);
    for (std::uint32_t m : members)
      if (present[m] == 1) e.add_torque(store.id_at(m), v(values + 3 * std::size_t(m)));
  };
  fns[1].record_kind = int(Load::Torque);

  fns[2].decl = {"add_force_at", {ArgKind::Vec3, ArgKind::Vec3}};
  fns[2].doc = "force at a world point, N (adds its torque about the centre of mass)";
  fns[2].call = [=](Stage& s, ObjectId id, const double* a) {
    engine(s).add_force(id, v(a), v(a + 3));
  };
  fns[2].record_kind = int(Load::ForceAtPoint);
  return fns;
}

inline RecordQueue engine_records() {
  RecordQueue q;
  q.open = [](Stage& s, std::size_t n) {
    std::span<RigidBodyEngine::LoadCommand> room = static_cast<RigidBodyEngine&>(s).open_loads(n);
    return std::span<LoadRecord>(reinterpret_cast<LoadRecord*>(room.data()), room.size());
  };
  q.close = [](Stage& s, std::size_t used) { static_cast<RigidBodyEngine&>(s).close_loads(used); };
  return q;
}

}  // namespace alloy::rigid
