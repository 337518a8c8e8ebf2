-- expect: line 4: object 'ball': kit.disk 'radius' must be a positive number, got -0.1
local kit = require "kit"

kit.disk { name = "ball", at = { 0, 1 }, radius = -0.1 }
