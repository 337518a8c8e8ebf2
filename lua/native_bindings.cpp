#include "lua/native_bindings.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <type_traits>

#include "lua/stage_abi.hpp"
#include "resolvers/rigid_body/engine.hpp"

namespace alloy::lua {

namespace {

const std::vector<FunctionDecl> kRigidBody = {
    {"add_force", {ArgKind::Vec3}},
    {"add_torque", {ArgKind::Vec3}},
    {"add_force_at", {ArgKind::Vec3, ArgKind::Vec3}},
};

// The prelude writes the rigid body's load records in place as
// abi::LoadRecord: the same bytes. The id packs slot and generation in that
// order (little-endian); the kinds follow RigidBodyEngine::Load.
using LoadCommand = rigid::RigidBodyEngine::LoadCommand;
using Load = rigid::RigidBodyEngine::Load;
static_assert(sizeof(LoadCommand) == sizeof(abi::LoadRecord) && offsetof(LoadCommand, slot) == 0 &&
              offsetof(LoadCommand, generation) == 4 &&
              offsetof(LoadCommand, value) == offsetof(abi::LoadRecord, vx) &&
              offsetof(LoadCommand, point) == offsetof(abi::LoadRecord, px) &&
              offsetof(LoadCommand, kind) == offsetof(abi::LoadRecord, kind) && sizeof(Load) == 1 &&
              std::is_trivially_copyable_v<LoadCommand>);
static_assert(std::endian::native == std::endian::little);

class RigidBodyTarget final : public NativeTarget {
 public:
  explicit RigidBodyTarget(rigid::RigidBodyEngine& rigid) : rigid_(rigid) {}
  void* open_records(std::size_t n) override {
    open_ = rigid_.open_loads(n);
    return open_.data();
  }
  std::string close_records(std::size_t used, const PropertyStore& store,
                            bool ids_checked) override {
    used = std::min(used, open_.size());
    if (!ids_checked)
      for (std::size_t r = 0; r < used; ++r) {
        const LoadCommand& c = open_[r];
        const ObjectId id = store.id_at(c.slot);
        if (!id || id.generation != c.generation) {
          rigid_.close_loads(0);
          open_ = {};
          const std::size_t fn = c.kind == Load::Torque ? 1 : c.kind == Load::ForceAtPoint ? 2 : 0;
          return "'" + kRigidBody[fn].name + "' on the object in slot " + std::to_string(c.slot) +
                 ", which was destroyed";
        }
      }
    rigid_.close_loads(used);
    open_ = {};
    return "";
  }
  int record_kind(std::int32_t fn) const override {
    switch (fn) {
      case 0:
        return int(Load::Force);
      case 1:
        return int(Load::Torque);
      case 2:
        return int(Load::ForceAtPoint);
    }
    return -1;
  }
  void call(std::int32_t fn, ObjectId object, const double* a) override {
    const Vec3 v{a[0], a[1], a[2]};
    switch (fn) {
      case 0:
        rigid_.add_force(object, v);
        return;
      case 1:
        rigid_.add_torque(object, v);
        return;
      case 2:
        rigid_.add_force(object, v, Vec3{a[3], a[4], a[5]});
        return;
    }
    throw AccessError("rigid_body has no interaction function #" + std::to_string(fn));
  }
  std::string perform(const double* b, std::size_t n, const PropertyStore& store,
                      bool alive_checked) override {
    for (std::size_t o = 0; o < n;) {
      const auto fn = std::int32_t(b[o]);
      const auto slot = std::uint32_t(b[o + 1]);
      if (alive_checked && fn == 0) {  // the fast path, as a native stage's loop over a column
        rigid_.add_force(slot, Vec3{b[o + 2], b[o + 3], b[o + 4]});
        o += 5;
        continue;
      }
      const ObjectId id = store.id_at(slot);
      if (!id)
        return "'" + kRigidBody[std::size_t(fn < 0 || fn > 2 ? 0 : fn)].name +
               "' on the object in slot " + std::to_string(slot) + ", which was destroyed";
      const Vec3 v{b[o + 2], b[o + 3], b[o + 4]};
      switch (fn) {
        case 0:
          rigid_.add_force(slot, v), o += 5;
          break;  // the fast path: the slot is alive
        case 1:
          rigid_.add_torque(id, v), o += 5;
          break;
        case 2:
          rigid_.add_force(id, v, Vec3{b[o + 5], b[o + 6], b[o + 7]}), o += 8;
          break;
        default:
          return "a command of an unknown interaction function";
      }
    }
    return "";
  }
  void perform_each(std::int32_t fn, std::span<const std::uint32_t> members,
                    const std::uint8_t* present, const double* v, int width,
                    const PropertyStore& store) override {
    if (width != 3) throw AccessError("rigid_body's interaction functions take a vec3");
    // The members are live (a column's, in this phase): the slot fast path,
    // as a native stage looping over a column uses it.
    switch (fn) {
      case 0:
        for (std::uint32_t s : members)
          if (present[s] == 1) rigid_.add_force(s, Vec3{v[3 * s], v[3 * s + 1], v[3 * s + 2]});
        return;
      case 1: {
        for (std::uint32_t s : members)
          if (present[s] == 1)
            rigid_.add_torque(store.id_at(s), Vec3{v[3 * s], v[3 * s + 1], v[3 * s + 2]});
        return;
      }
    }
    throw AccessError("rigid_body's interaction function #" + std::to_string(fn) +
                      " has no bulk form");
  }

 private:
  rigid::RigidBodyEngine& rigid_;
  std::span<LoadCommand> open_;  // the room of the current call
};

}  // namespace

const std::vector<FunctionDecl>* native_functions(std::string_view resolver) {
  if (resolver == "rigid_body") return &kRigidBody;
  return nullptr;
}

std::unique_ptr<NativeTarget> bind_native_target(PluginContext& ctx) {
  if (ctx.info().target == "rigid_body")
    return std::make_unique<RigidBodyTarget>(ctx.target<rigid::RigidBodyEngine>());
  throw InputError("Lua interactions cannot queue on the native resolver '" + ctx.info().target +
                   "' (Lua can reach: rigid_body)");
}

bool native_derived_readable(std::string_view set) {
  return set == "collisions";
}

}  // namespace alloy::lua
