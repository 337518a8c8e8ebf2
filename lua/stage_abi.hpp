// The data a Lua stage's host code (stage_prelude.lua) shares with C++ through
// LuaJIT's FFI: plain C structs, declared once here and once, identically, in
// the prelude's ffi.cdef (static_asserts below keep the two in step).
//
// Only the prelude sees these. A mod gets Lua proxies built on them that
// check every index and every value; it never holds a pointer. All pointers
// here are valid during one call of one stage: C++ fills them when the stage
// asks for a column (fetch) and clears them when the call ends, whichever
// way (LuaStage::end_call). The prelude converts a mod's arguments before it
// checks that the call is on and takes a pointer, so that no code of the mod
// runs while it holds one (docs/architecture.md, "The Lua boundary").
#pragma once

#include <cstddef>
#include <cstdint>

#include "runtime/math.hpp"
#include "runtime/object_id.hpp"

namespace alloy::lua::abi {

/// What a column holds, as the prelude reads it.
enum ColumnKind : std::int32_t {
  kNumber = 0,
  kInteger = 1,
  kBool = 2,
  kVec3 = 3,
  kQuat = 4,
  kEnum = 5,
  kRef = 6,
  kOther = 7,  ///< string, reflist: read through a slow C call
};

/// One column as a stage sees it in one call.
struct Column {
  /// The values, one per object slot (the column's own storage, or a Lua
  /// derived set's output). Which member is valid follows `kind`.
  union {
    const double* num;
    const std::int64_t* integer;
    const std::uint8_t* boolean;
    const Vec3* vec3;
    const Quat* quat;
    const std::int32_t* enumv;
    const ObjectId* ref;
    const void* any;
  };
  const std::uint32_t*
      members;      ///< slots of the objects carrying it (in the stage's area), ascending
  double* out_num;  ///< a derived set's own outputs, writable by it alone
  Vec3* out_vec3;
  std::uint8_t* out_present;
  std::uint32_t n;      ///< slots while fetched in the current call, 0 otherwise
  std::uint32_t count;  ///< members while fetched, 0 otherwise
};

/// The stage's current call: numbers it reads, scratch for the arguments of
/// an interaction function, and lists handed out for the call.
struct Call {
  double dt = 0, time = 0, step = 0;
  /// Doubles used / available in buf (records used / available in loads,
  /// when the target takes them in place). Doubles, not integers: the prelude
  /// reads and writes them back in hot loops, and a uint32 field doing that
  /// makes LuaJIT's traces type-unstable (they never compile).
  double buf_len = 0, buf_cap = 0;
  /// An interaction's commands of this call, appended by the prelude as
  /// records {function, slot, arguments...} and performed by C++ when the
  /// call returns (all of them, or none if the call failed).
  double* buf = nullptr;
  const double* cmd = nullptr;     ///< a resolver's queued commands of one function
  const void* contacts = nullptr;  ///< Contact[contact_count]
  std::uint32_t cmd_count = 0, cmd_stride = 0;
  std::uint32_t contact_count = 0;
  std::uint32_t slots = 0;   ///< object slots in the world
  std::int32_t in_call = 0;  ///< 1 while the stage runs
  /// Moves when a call starts and when it ends: a list, or a function
  /// entered, in one call is refused in any other.
  std::uint32_t epoch = 0;
  /// An interaction's per-slot ids, `slots` of them: the live object's
  /// ObjectId packed as its generation << 32 | slot, or 0 for a free slot
  /// (0 is never a live generation). Its functions check a slot against them
  /// as they queue a command, and copy the id into a load record (kept
  /// between calls, rebuilt when objects come or go).
  const std::uint64_t* ids = nullptr;
  /// An interaction on a target that takes records in place (the rigid
  /// body): the target's own queue, room for buf_cap records of which buf_len
  /// are written, while the call runs; else null (records go to buf).
  void* loads = nullptr;
};

/// A load record of a target that takes them in place: the runtime's
/// LoadRecord (runtime/interaction_function.hpp; native_bindings.cpp asserts
/// the layout), which such a resolver's queue holds. `id` is the slot and generation, as Call::ids
/// holds them.
struct LoadRecord {
  std::uint64_t id;
  double vx, vy, vz;  ///< force or torque
  double px, py, pz;  ///< the point of a force at a point
  std::uint8_t kind;  ///< 0 force, 1 force at a point, 2 torque
};

/// A contact pair of the collisions derived set, copied for Lua.
struct Contact {
  std::uint32_t a, b;    ///< slots, a < b
  std::int32_t points;   ///< contact points (0 for ended pairs)
  std::int32_t began;    ///< 1 if the pair began at the set's last update
  double speed;          ///< approach speed along the normal, m/s
  double depth;          ///< deepest penetration, m
  double impulse;        ///< normal impulse of the rigid body's last advance, N*s
  double total_impulse;  ///< normal impulse since the pair began, N*s
  Vec3 normal;           ///< of the first point, from b towards a
  Vec3 point;            ///< the first point, m
};

/// An interaction's bulk buffer: one value per object slot for one of its
/// target's interaction functions (`add_force_each`), queued for the members
/// of one column when the call returns. `present` is 0 for a member not yet
/// written, 1 for a member written, 2 for a slot that is not a member (a
/// write there is refused at the mod's line).
struct Bulk {
  double* values;         ///< width doubles per slot
  std::uint8_t* present;  ///< one per slot
  std::uint32_t n;        ///< slots while valid in the current call, 0 otherwise
  std::int32_t width;     ///< 1 (a number) or 3 (a vec3)
  std::int32_t function;  ///< the target's interaction function
  std::int32_t column;    ///< the column whose members it covers
};

/// A mod's budget as its ticks see it (budget_ticks.hpp).
struct Budget {
  /// Ticks left before the host checks the budgets (at most a quantum, a
  /// thousand). An int16, neither a float, an int32 nor a double: the tick
  /// stores it in every loop iteration of a mod, and LuaJIT takes a store as
  /// possibly changing any field of the same type (signed or not). An int32
  /// store would make it reload the uint32 counts and sizes of the columns
  /// the loop reads; a double store would make it reload the tick itself
  /// after every double the loop stores (load records), a chain through
  /// memory in every iteration. No other 16-bit integer is stored in a loop,
  /// so LuaJIT keeps the count in a register, and it narrows the decrement
  /// to integer arithmetic: a float (the previous type) cost a convert -
  /// subtract - convert chain of ~13 cycles' latency per iteration.
  std::int16_t ticks = 0;
  std::int16_t unused = 0;
  std::int32_t stopped = 0;  ///< 1 once the mod is stopped: every tick fails
};

/// Entry points of the fast path, called by the prelude through the FFI.
/// `stage` is the C++ stage (LuaStage*); `slot` a Lua number checked here.
/// Each returns 0 on success, else the stage holds a message (last_error).
/// None throws (each ends in catch (...)), and none calls into Lua: they are
/// called from inside the Lua VM, which an exception must not cross.
struct Api {
  std::int32_t (*fetch)(void* stage, std::int32_t column) noexcept;
  std::int32_t (*set_scalar)(void* stage, std::int32_t column, double slot, double v) noexcept;
  std::int32_t (*set_vec3)(void* stage, std::int32_t column, double slot, double x, double y,
                           double z) noexcept;
  std::int32_t (*set_quat)(void* stage, std::int32_t column, double slot, double w, double x,
                           double y, double z) noexcept;
  std::int32_t (*has)(void* stage, std::int32_t column,
                      double slot) noexcept;   ///< 1, 0, or -1 on error
  std::int32_t (*grow)(void* stage) noexcept;  ///< more room in Call::buf
  std::int32_t (*commands)(void* stage, std::int32_t function) noexcept;
  std::int32_t (*contacts)(void* stage, std::int32_t which) noexcept;
  /// A bulk buffer (Bulk) of `function` over the members of `column`: its
  /// index, or -1 on error.
  std::int32_t (*bulk)(void* stage, std::int32_t function, std::int32_t column) noexcept;
};

static_assert(sizeof(Vec3) == 24 && sizeof(Quat) == 32 && sizeof(ObjectId) == 8);
static_assert(offsetof(Column, members) == 8 && offsetof(Column, n) == 40 && sizeof(Column) == 48);
static_assert(offsetof(Call, buf_len) == 24 && offsetof(Call, buf) == 40 &&
              offsetof(Call, in_call) == 80 && offsetof(Call, ids) == 88 &&
              offsetof(Call, loads) == 96 && sizeof(Call) == 104);
static_assert(offsetof(LoadRecord, vx) == 8 && offsetof(LoadRecord, px) == 32 &&
              offsetof(LoadRecord, kind) == 56 && sizeof(LoadRecord) == 64);
static_assert(offsetof(Bulk, n) == 16 && offsetof(Bulk, column) == 28 && sizeof(Bulk) == 32);
static_assert(offsetof(Contact, speed) == 16 && offsetof(Contact, normal) == 48 &&
              sizeof(Contact) == 96);

/// The prelude's ffi.cdef of the structs above.
inline constexpr const char* kCdef = R"C(
typedef struct alloy_vec3 { double x, y, z; } alloy_vec3;
typedef struct alloy_quat { double w, x, y, z; } alloy_quat;
typedef struct alloy_ref { uint32_t index, generation; } alloy_ref;
typedef struct alloy_column {
  union { const double* num; const int64_t* integer; const uint8_t* boolean;
          const alloy_vec3* vec3; const alloy_quat* quat; const int32_t* enumv;
          const alloy_ref* ref; const void* any; };
  const uint32_t* members;
  double* out_num; alloy_vec3* out_vec3; uint8_t* out_present;
  uint32_t n, count;
} alloy_column;
typedef struct alloy_call {
  double dt, time, step;
  double buf_len, buf_cap;
  double* buf; const double* cmd; const void* contacts;
  uint32_t cmd_count, cmd_stride, contact_count, slots;
  int32_t in_call; uint32_t epoch;
  const uint64_t* ids;
  void* loads;
} alloy_call;
typedef struct alloy_load {
  uint64_t id; double vx, vy, vz, px, py, pz; uint8_t kind;
} alloy_load;
typedef struct alloy_contact {
  uint32_t a, b; int32_t points, began;
  double speed, depth, impulse, total_impulse;
  alloy_vec3 normal, point;
} alloy_contact;
typedef struct alloy_bulk {
  double* values; uint8_t* present;
  uint32_t n; int32_t width, fn, column;
} alloy_bulk;
typedef struct alloy_budget { int16_t ticks, unused; int32_t stopped; } alloy_budget;
typedef struct alloy_api {
  int32_t (*fetch)(void*, int32_t);
  int32_t (*set_scalar)(void*, int32_t, double, double);
  int32_t (*set_vec3)(void*, int32_t, double, double, double, double);
  int32_t (*set_quat)(void*, int32_t, double, double, double, double, double);
  int32_t (*has)(void*, int32_t, double);
  int32_t (*grow)(void*);
  int32_t (*commands)(void*, int32_t);
  int32_t (*contacts)(void*, int32_t);
  int32_t (*bulk)(void*, int32_t, int32_t);
} alloy_api;
)C";

}  // namespace alloy::lua::abi
