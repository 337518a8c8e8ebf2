// Interaction functions as data (paper 3.2: an interaction "queues commands"
// on its target resolver). A resolver declares in its plugin definition the
// functions other stages may call on it: their names, their arguments, and how
// to perform them. Bindings (lua/) read the declaration and name no resolver;
// two engines that provide the same thing (StageInfo::provides, e.g. two
// rigid bodies) declare the same functions, and the registry checks it, so
// that every mod works unchanged on either engine.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/math.hpp"
#include "runtime/object_id.hpp"

namespace alloy {

class Stage;
class PropertyStore;

/// The kind of one argument of an interaction function, after the object.
enum class ArgKind : std::uint8_t { Number, Object, Vec3 };
std::string_view to_string(ArgKind kind);
/// Doubles one argument takes in a queued command.
inline int width(ArgKind k) {
  return k == ArgKind::Vec3 ? 3 : 1;
}

/// An interaction function's signature: a name and the arguments after the object.
struct FunctionDecl {
  std::string name;
  std::vector<ArgKind> args;
  friend bool operator==(const FunctionDecl&, const FunctionDecl&) = default;
};

/// Doubles all of `args` take in a queued command.
inline int width(const std::vector<ArgKind>& args) {
  int n = 0;
  for (ArgKind a : args) n += width(a);
  return n;
}

/// One record of a resolver's in-place load queue: the layout a binding (the
/// Lua prelude) writes directly into the resolver's own storage, with no call
/// per record. An engine whose queue entry has another type asserts that it
/// has this layout (resolvers/rigid_body/engine_functions.hpp).
struct LoadRecord {
  std::uint32_t slot;
  std::uint32_t generation;  ///< the object's, as its ObjectId holds it
  Vec3 value;                ///< force or torque
  Vec3 point;                ///< the world point of a force at a point
  std::uint8_t kind;         ///< InteractionFunction::record_kind of the function
};

/// A resolver's in-place queue of LoadRecords. open(stage, n): room for n
/// records after those queued when the room was first opened (asked again,
/// more room with the records written so far kept; the span may move).
/// close(stage, used): keeps the first `used` and closes the room. Records are
/// performed by the resolver's next advance, like calls.
struct RecordQueue {
  std::function<std::span<LoadRecord>(Stage& target, std::size_t n)> open;
  std::function<void(Stage& target, std::size_t used)> close;
  explicit operator bool() const { return bool(open) && bool(close); }
};

/// One interaction function as a resolver declares it. The callables get the
/// resolver's own stage (the one its plugin's `create` made: a binding never
/// passes another plugin's stage) and the packed arguments, `width(args)`
/// doubles in the order of `args` (a vec3 as x, y, z; an object as its slot
/// in the property store, holding a live object when the call is made).
struct InteractionFunction {
  FunctionDecl decl;  ///< name and arguments after the object
  std::string doc;    ///< one line for `alloy plugins` and docs
  /// Queues the call for `object`. Throws AccessError for an object that is
  /// gone, InputError for arguments the resolver refuses. Null for a resolver
  /// defined in Lua (its mod's runtime performs the calls).
  std::function<void(Stage& target, ObjectId object, const double* args)> call;
  /// Optional fast form for an object known to be alive (a slot from a
  /// column's member list in the same phase): no liveness check.
  std::function<void(Stage& target, std::uint32_t slot, const double* args)> call_live;
  /// Optional bulk form over a column's members (all alive): the call for
  /// each slot s in `members` whose present[s] is 1, with the arguments at
  /// values + width * s. Without it a binding loops over call_live / call.
  std::function<void(Stage& target, std::span<const std::uint32_t> members,
                     const std::uint8_t* present, const double* values, const PropertyStore& store)>
      each;
  /// The LoadRecord::kind this function is written as in the resolver's
  /// RecordQueue (PluginDef::records), or -1 if it is only called.
  int record_kind = -1;
};

/// The signatures of `fns`, in order.
inline std::vector<FunctionDecl> declarations(const std::vector<InteractionFunction>& fns) {
  std::vector<FunctionDecl> out;
  out.reserve(fns.size());
  for (const auto& f : fns) out.push_back(f.decl);
  return out;
}

/// "add_force(vec3)" for messages and listings.
std::string signature(const FunctionDecl& f);

}  // namespace alloy
