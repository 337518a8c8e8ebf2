-- A bar held by a pin is let go at t = 0.5 s: the scene's timeline of input.
local kit = require "kit"
world { dt = 1 / 240, seconds = 1 }
kit.bar { name = "bar", material = "steel", at = { 0, 1 }, length = 0.2, width = 0.02,
          props = { pinned = true } }
at(0.5, "bar", { pinned = false })
