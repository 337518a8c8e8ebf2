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
  },
}

local motor = require "motor.layout" ()

at(motor.slider_release, "slider", { pinned = false })
at(5.0, "battery", { emf = 0 })
