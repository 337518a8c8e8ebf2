-- adv20: mods/motor/scene.lua with magnetic_forces' coils_from_current off
-- (the paper's path: the pull from the magnetism resolver's pole strength).
world {
  dt = 1 / 240, seconds = 10,
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    electricity = { induction_order = 2 },
    magnetic_forces = { coils_from_current = false },
  },
}
local motor = require "motor.layout" ()
at(motor.slider_release, "slider", { pinned = false })
