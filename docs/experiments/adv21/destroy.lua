-- adv21: destroy a part whose predicted connection is queued: glide_slow.lua
-- (touch in step 5 at fraction 0.3, predicted at step 4) with a second body far
-- away (so that the rigid body stays); destroy_script.txt deletes the bar in
-- the viewer after step 4. Box2D: add use = { rigid_body = "rigid_body.box2d" }.
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
kit.disk { name = "other", material = "wood", at = { 1, 1 }, radius = 0.02 }
