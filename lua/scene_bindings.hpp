// The three statements of a scene, as seen from Lua:
//
//   world  { dt = 1/240, seconds = 5, name = "...", description = "...",
//            plugins = {...}, settings = { ["gravity.uniform"] = { g = {0, -9.81, 0} } },
//            every = { collisions = 2 } }
//   object { name = "ball", position = {0, 1}, shape = "sphere", radius = 0.1, mass = 1 }
//   at(1.0, "switch", { pinned = false })   -- the scene's timeline: input, as by a player's hand
//   swap(5.0, "orbit", "gravity.nbody", "gravity.uniform")   -- a resolver swap on the timeline
//
// All only record (collect, then apply): the values go into a SceneRecord
// with the line of the scene statement that asked for them, found host-side
// from the Lua stack (the innermost frame outside library mods), so an object
// made inside kit.bar{} carries the line of the kit.bar{} call.
#pragma once

#include "lua/scene_record.hpp"

struct lua_State;

namespace alloy::lua {

class LuaHost;

class SceneRecorder {
 public:
  explicit SceneRecorder(LuaHost& host) : host_(host) {}
  SceneRecorder(const SceneRecorder&) = delete;
  SceneRecorder& operator=(const SceneRecorder&) = delete;

  /// Adds `world`, `object` and `at` to the environment table at `env`. The
  /// recorder must outlive every call of them (it does: both die with the load).
  void install(lua_State* L, int env);

  SceneRecord& record() { return record_; }

 private:
  static int world_fn(lua_State* L);
  static int object_fn(lua_State* L);
  static int at_fn(lua_State* L);
  static int swap_fn(lua_State* L);
  int record_world(lua_State* L);
  int record_object(lua_State* L);
  int record_input(lua_State* L);
  int record_swap(lua_State* L);

  LuaHost& host_;
  SceneRecord record_;
};

}  // namespace alloy::lua
