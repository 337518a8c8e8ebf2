-- expect: line 5: object 'axle': 'body_a' refers to 'wheal', but no object has that name (did you mean 'wheel'?)
local kit = require "kit"

kit.disk { name = "wheel", at = { 0, 1 }, radius = 0.1 }
kit.pin { name = "axle", part = "wheal", at = { 0, 1 } }
