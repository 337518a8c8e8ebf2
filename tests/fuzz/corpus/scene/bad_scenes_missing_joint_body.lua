-- expect: line 5: object 'pivot': 'body_b' refers to 'anchor_block', but no object has that name (did you mean 'anchor_blok'?)
local kit = require "kit"
kit.bar { name = "arm", at = { 1, 2 }, length = 1 }
kit.bar { name = "anchor_blok", at = { 0, 2 }, length = 0.2 }
kit.hinge { name = "pivot", a = "arm", b = "anchor_block", anchor = { 0.5, 2 } }
