-- adv20: mods/motor/scene.lua with the rigid body every 3-th step.
world {
  dt = 1 / 240, seconds = 10, every = { rigid_body = 3 },
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    electricity = { induction_order = 2 },
  },
}
local motor = require "motor.layout" ()
at(motor.slider_release, "slider", { pinned = false })
