-- Two balls dropped side by side: the one in the "moon" area falls under the
-- moon's gravity, the other under the world's. The areas are world settings.
local kit = require "kit"
world {
  dt = 1 / 240,
  areas = {
    { name = "moon", center = { -1, 1 }, half_extents = { 0.5, 2 },
      plugins = { "gravity.uniform" },
      settings = { ["gravity.uniform"] = { g = { 0, -1.62 } } } },
  },
}
kit.disk { name = "moon_ball", material = "steel", at = { -1, 2 }, radius = 0.05 }
kit.disk { name = "earth_ball", material = "steel", at = { 1, 2 }, radius = 0.05 }
