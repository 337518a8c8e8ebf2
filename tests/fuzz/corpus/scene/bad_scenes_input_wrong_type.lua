-- expect: line 6: object 'switch': 'pinned' expects true or false, got the number 0
local kit = require "kit"

kit.bar { name = "switch", material = "brass", at = { 0, 1 }, length = 0.2, width = 0.02,
          props = { pinned = true } }
at(1.0, "switch", { pinned = 0 })
