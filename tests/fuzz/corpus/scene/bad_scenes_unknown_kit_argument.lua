-- expect: line 4: object 'ball': kit.disk has no argument 'raduis' (did you mean 'radius'?)
local kit = require "kit"

kit.disk { name = "ball", at = { 0, 1 }, raduis = 0.1 }
