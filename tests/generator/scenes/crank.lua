-- The generator (mods/generator/layout.lua) with no timeline: the tests set
-- the hand's torque on the crank themselves (tests/generator/generator_test.cpp).
world {
  name = "generator_crank",
  dt = 1 / 240,
  seconds = 6,
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    electricity = { induction_order = 2 },  -- as mods/generator names it (session 17)
    magnetic_forces = { near_field = false },  -- as mods/generator names it (session 20)
  },
}
require "generator.layout" ()
