-- expect: line 4: plugin 'gravity.uniform' has no setting 'gg' (did you mean 'g'?)
local kit = require "kit"

world { seconds = 1, settings = { ["gravity.uniform"] = { gg = { 0, -9.81 } } } }
kit.disk { name = "ball", at = { 0, 1 }, radius = 0.1 }
