-- The motor run for 5 s, then its battery is taken away (its emf set to
-- 0 V): no current flows, both coils die, and the rotor runs down against
-- its bearing and stops where the bias magnet holds it.
world {
  name = "motor_battery_off",
  description = "the motor, its battery removed at t = 5 s: it runs down and stops",
  dt = 1 / 240,
  seconds = 10,
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
at(5.0, "battery", { emf = 0 })
