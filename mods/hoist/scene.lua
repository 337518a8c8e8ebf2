-- The motor lifts a load: a 100 g steel weight on a string wound on its
-- axle. At 0.1 s the sliding contact is let go, the rotor starts, and the
-- string winds in. `alloy run mods/hoist` reports the load's height.
world {
  name = "hoist",
  description = "the motor of mods/motor winds a string on its axle and lifts a 100 g load",
  dt = 1 / 240,
  seconds = 10,
  report = { "axle.angular_velocity.z@1", "load.position.y@1" },
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    -- Second-order induction (the EMF from the motion's present velocity and
    -- acceleration, docs/electricity.md "Induction"), named here so that the
    -- figures in docs/motor.md are the ones this scene runs with.
    electricity = { induction_order = 2 },
  },
}

local hoist = require "hoist.layout" ()

for _, slider in ipairs(hoist.sliders) do at(hoist.slider_release, slider, { pinned = false }) end
