-- expect: line 5: '}' expected near 'at'
local kit = require "kit"

kit.floor { name = "floor", at = { 0, 0 }, size = { 4, 0.1 } }
kit.bar { name = "arm" at = { 1, 2 }, length = 1 }
