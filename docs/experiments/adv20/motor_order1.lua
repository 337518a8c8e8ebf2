-- adv20: mods/motor/scene.lua with induction_order = 1.
world {
  dt = 1 / 240, seconds = 10,
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    electricity = { induction_order = 1 },
  },
}
local motor = require "motor.layout" ()
at(motor.slider_release, "slider", { pinned = false })
