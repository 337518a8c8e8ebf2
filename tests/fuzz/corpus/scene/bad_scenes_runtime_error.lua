-- expect: line 6: attempt to call global 'spoke_count' (a nil value)
local kit = require "kit"

kit.disk { name = "hub", at = { 0, 1 }, radius = 0.1 }
-- spoke_count was never defined: a plain runtime error in the scene.
for i = 1, spoke_count() do
  kit.bar { name = "spoke" .. i, at = { 0, 1 }, length = 0.3 }
end
