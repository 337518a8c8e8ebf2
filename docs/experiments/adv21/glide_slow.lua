-- adv21: glide.lua at 0.2 m/s, touch inside step 5 at fraction 0.3 (1/240 s):
-- with ahead the touch is predicted at the end of step 4 and connected in
-- step 5; without, seen at step 5's end and connected in step 6. The bar
-- bounces off (restitution) and comes back? No: no gravity, it leaves.
local kit = require "kit"
local V = 0.2
local GAP = (4 + 0.3) / 240 * V
world { dt = 1/240, seconds = 0.1,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = true } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0.01, 0 } }
kit.bar { name = "bar", material = "brass", at = { -GAP - 0.05, 0 }, length = 0.1, width = 0.01,
          velocity = { V, 0 }, props = { restitution = 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar" }
