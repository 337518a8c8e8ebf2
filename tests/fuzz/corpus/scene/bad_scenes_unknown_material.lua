-- expect: line 5: object 'arm': unknown material 'stel' (did you mean 'steel'?)
local kit = require "kit"

kit.floor { name = "floor", at = { 0, 0 }, size = { 4, 0.1 } }
kit.bar { name = "arm", material = "stel", at = { 1, 2 }, length = 1 }
