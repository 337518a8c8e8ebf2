-- expect: line 6: object 'swich': at(): no object is called 'swich'
local kit = require "kit"

kit.bar { name = "switch", material = "brass", at = { 0, 1 }, length = 0.2, width = 0.02,
          props = { pinned = true } }
at(1.0, "swich", { pinned = false })
