-- adv20: mods/motor/scene.lua with the rigid body every 3rd step and coils_from_current off.
world {
  dt = 1 / 240, seconds = 10, every = { rigid_body = 3 },
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    electricity = { induction_order = 2 }, magnetic_forces = { coils_from_current = false },
  },
}
local motor = require "motor.layout" ()
at(motor.slider_release, "slider", { pinned = false })
