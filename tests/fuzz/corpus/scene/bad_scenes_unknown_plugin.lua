-- expect: line 4: world: 'every' for unknown plugin 'colisions' (did you mean 'collisions'?)
local kit = require "kit"

world { seconds = 1, every = { colisions = 2 } }
kit.disk { name = "ball", at = { 0, 1 }, radius = 0.1 }
