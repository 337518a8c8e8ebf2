-- Two rigid-body engines in one world (issue 15): the left table is simulated
-- by ODE (the global rigid_body), the right one by Box2D (the area "right",
-- 0 <= x <= 2, lists rigid_body.box2d and its collisions). A ball rolls along
-- the left table onto the right one: when its centre crosses x = 0 it leaves
-- ODE and Box2D takes it over with its pose, velocity and spin
-- (docs/box2d.md, "Areas"). The tables' tops are level and meet at x = 0, so
-- the ball always rests on a table of the engine that simulates it.
-- tests/two_engines checks that it crosses, keeps its speed and stays on the
-- right table.
local kit = require "kit"

world {
  name = "two_engines",
  description = "two tables, ODE on the left and Box2D on the right, a ball rolling across",
  dt = 1 / 240,
  seconds = 4,
  settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } } },
  areas = {
    { name = "right", center = { 1, 0.5, 0 }, half_extents = { 1, 1, 1 },
      plugins = { "rigid_body.box2d", "collisions.box2d", "rigid_body_from_gravity" } },
  },
}

-- Table tops, level at y = 0.8, meeting at x = 0.
kit.floor { name = "left_table", at = { -0.75, 0.775 }, size = { 1.5, 0.05 } }
kit.floor { name = "right_table", at = { 0.75, 0.775 }, size = { 1.5, 0.05 } }

-- A wooden ball (a disk in the plane) set rolling to the right without
-- slipping: v = -spin * radius = 0.6 m/s. It crosses x = 0 at t = 2 s.
kit.disk { name = "ball", material = "wood", at = { -1.2, 0.84 }, radius = 0.04,
           velocity = { 0.6, 0, 0 }, spin = -15 }
