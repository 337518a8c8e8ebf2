// What Lua stages may reach of the native plugins, as the plugins declare it
// (runtime/interaction_function.hpp): a native resolver's interaction
// functions (PluginDef::functions, e.g. the rigid body's add_force), and the
// native derived sets that are contact sets (PluginDef::contacts), which
// `w:contacts(...)` reads. One generic binding serves every resolver: lua/
// names none, and a second engine that provides the same thing is bound the
// same way. Lua never holds a pointer to a native stage.
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
  /// The functions, in the order the prelude numbers them.
  virtual const std::vector<FunctionDecl>& functions() const = 0;
  /// Queues function `fn` (an index into functions()) for `object`
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
  virtual void* open_records(std::size_t n) = 0;
  /// Keeps the first `used` records of the open room and closes it. Unless
  /// `ids_checked` (the prelude checked every id against the store as it is
  /// now), each record's object is checked first; if one is gone, no record
  /// is kept and what was refused is returned.
  virtual std::string close_records(std::size_t used, const PropertyStore& store,
                                    bool ids_checked) = 0;
  /// The record kind (abi::LoadRecord::kind) of interaction function `fn`
  /// written in place, or -1 if it is queued as a command.
  virtual int record_kind(std::int32_t fn) const = 0;
  /// Performs a bulk buffer of function `fn` (one argument): for each slot
  /// in `members` (live objects, from a column fetched in this call) whose
  /// `present` is 1, the call with the slot's `width` values. The values
  /// were checked by the prelude.
  virtual void perform_each(std::int32_t fn, std::span<const std::uint32_t> members,
                            const std::uint8_t* present, const double* values, int width,
                            const PropertyStore& store) = 0;
};

/// The native resolver `name` if Lua may queue on it (a registered resolver
/// whose interaction functions have native callables), else nullptr.
const PluginDef* native_resolver(const PluginRegistry& registry, std::string_view name);

/// Binds the target of the interaction being created by `ctx`: the stage
/// active for the interaction's area, with the functions its plugin declares.
std::unique_ptr<NativeTarget> bind_native_target(PluginContext& ctx);

/// Whether `set` names a native derived set a Lua stage may declare in
/// `derived` (a contact set).
bool native_derived_readable(const PluginRegistry& registry, std::string_view set);

/// For messages: the native resolvers Lua may queue on, and the contact sets
/// it may read, as "a, b" (or "none").
std::string native_resolver_names(const PluginRegistry& registry);
std::string native_contact_set_names(const PluginRegistry& registry);

}  // namespace alloy::lua
