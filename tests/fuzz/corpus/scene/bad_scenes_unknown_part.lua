-- expect: line 5: object 'bracket': unknown part 'kit.bars' (did you mean 'kit.bar'?)
local kit = require "kit"

kit.floor { name = "floor", at = { 0, 0 }, size = { 4, 0.1 } }
kit.bars { name = "bracket", at = { 1, 2 }, length = 1 }
