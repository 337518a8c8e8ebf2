// What Lua stages may reach of the native plugins: a small, declared set of
// interaction functions per native resolver (the rigid body's add_force and
// add_torque), and the native derived sets they may read (collisions). Each
// binding is a few lines over the resolver's own C++ interaction functions;
// Lua never holds a pointer to a native stage.
//
//   rigid_body   add_force(i, f)          force at the centre of mass, N
//                add_torque(i, t)         torque, N m, world frame
//                add_force_at(i, f, p)    force at the world point p, N
//   collisions   w:contacts("began" | "ongoing" | "ended" | "touching")
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "lua/mod_state.hpp"
#include "runtime/plugin_registry.hpp"
#include "runtime/property_store.hpp"

namespace alloy::lua {

/// A native resolver's interaction functions, bound for one Lua interaction.
class NativeTarget {
 public:
  virtual ~NativeTarget() = default;
  /// Queues function `fn` (an index into native_functions()) for `object`
  /// with its packed arguments. Throws AccessError or InputError.
  virtual void call(std::int32_t fn, ObjectId object, const double* args) = 0;
  /// Performs a call's command records {function, slot, arguments...}
  /// [b, b + n), checked by the prelude, the objects being alive included if
  /// `alive_checked` (else they are checked here). Returns "" or what was
  /// refused.
  virtual std::string perform(const double* b, std::size_t n, const PropertyStore& store,
                              bool alive_checked) = 0;
  /// In-place queueing: room for `n` load records (abi::LoadRecord) in the
  /// target's own queue, after those queued before the room was first opened;
  /// asked again, more room with the records written so far kept (the
  /// pointer may move). nullptr if the target takes no records in place.
  virtual void* open_records(std::size_t n) { (void)n; return nullptr; }
  /// Keeps the first `used` records of the open room and closes it. Unless
  /// `ids_checked` (the prelude checked every id against the store as it is
  /// now), each record's object is checked first; if one is gone, no record
  /// is kept and what was refused is returned.
  virtual std::string close_records(std::size_t used, const PropertyStore& store,
                                    bool ids_checked) {
    (void)used, (void)store, (void)ids_checked;
    return "";
  }
  /// The record kind (abi::LoadRecord::kind) of interaction function `fn`
  /// written in place, or -1 if it is queued as a command.
  virtual int record_kind(std::int32_t fn) const { (void)fn; return -1; }
  /// Performs a bulk buffer of function `fn` (one argument): for each slot
  /// in `members` (live objects, from a column fetched in this call) whose
  /// `present` is 1, the call with the slot's `width` values. The values
  /// were checked by the prelude.
  virtual void perform_each(std::int32_t fn, std::span<const std::uint32_t> members,
                            const std::uint8_t* present, const double* values, int width,
                            const PropertyStore& store) = 0;
};

/// The interaction functions Lua may call on the native resolver `resolver`,
/// or nullptr if it exposes none.
const std::vector<FunctionDecl>* native_functions(std::string_view resolver);

/// Binds the target of the interaction being created by `ctx` (its info's
/// target must have native_functions()).
std::unique_ptr<NativeTarget> bind_native_target(PluginContext& ctx);

/// Native derived sets a Lua stage may declare in `derived`.
bool native_derived_readable(std::string_view set);

}  // namespace alloy::lua
