-- expect: line 4: object 'arm': kit.bar needs 'length'
local kit = require "kit"

kit.bar { name = "arm", material = "brass", at = { 0, 1 } }
