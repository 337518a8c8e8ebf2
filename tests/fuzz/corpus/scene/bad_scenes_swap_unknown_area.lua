-- expect: line 5: swap(): no area is called 'orbit'
local kit = require "kit"
world { dt = 1 / 240 }
kit.disk { name = "ball", material = "steel", at = { 0, 1 }, radius = 0.05 }
swap(1.0, "orbit", "gravity.uniform", "gravity.uniform")
