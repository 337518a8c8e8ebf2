-- adv20: mods/doorbell/scene.lua with magnetic_forces' coils_from_current
-- off (the paper's path: the pull from the magnetism resolver's pole strength).
world {
  dt = 1 / 240, seconds = 10,
  settings = {
    ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
    rigid_body = { solver = "step" },
    magnetic_forces = { coils_from_current = false },
  },
}
require "doorbell.layout" ()
at(0.5, "switch_bar", { pinned = false })
