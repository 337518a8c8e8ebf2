-- expect: line 6: object 'ball': duplicate name: 'ball' is already the name of the object at
local kit = require "kit"

kit.disk { name = "ball", material = "rubber", at = { 0, 1 }, radius = 0.1 }
kit.disk { name = "other", material = "rubber", at = { 1, 1 }, radius = 0.1 }
kit.disk { name = "ball", material = "steel", at = { 2, 1 }, radius = 0.1 }
