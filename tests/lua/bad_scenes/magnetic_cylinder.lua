-- expect: line 4: object 'wheel': a cylinder cannot be magnetic
local kit = require "kit"

kit.cylinder { name = "wheel", material = "iron", at = { 0, 1 }, radius = 0.1, magnetic = true }
