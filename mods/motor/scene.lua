-- The electric motor: at t = 0.1 s the sliding contact is let go; it falls
-- onto the spokes, closes the first circuit, and the rotor starts to turn
-- anticlockwise by itself, steadily from about frame 200 (0.83 s).
-- `alloy run mods/motor` narrates it; docs/motor.md says what to look for.
world {
  name = "motor",
  description = "the paper's electric motor (4.2): the sliding contact falls, the rotor turns",
  dt = 1 / 240,
  seconds = 10,
  -- once a simulated second, the rotor's speed (rad/s, + is anticlockwise)
  report = { "axle.angular_velocity.z@1" },
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    -- ODE's exact solver: on this small mechanism (a rotor, a slider, one
    -- contact) it gives QuickStep's speed to 0.02 % in two thirds of the
    -- time (docs/performance.md, "Coupled scenes").
    rigid_body = { solver = "step" },
    -- Second-order induction (the EMF from the motion's present velocity and
    -- acceleration, docs/electricity.md "Induction"), named here so that the
    -- figures in docs/motor.md are the ones this scene runs with.
    electricity = { induction_order = 2 },
  },
}

local motor = require "motor.layout" ()

for _, slider in ipairs(motor.sliders) do at(motor.slider_release, slider, { pinned = false }) end
