-- adv21: on Box2D at 1/60 s a brass bar gliding at 0.2 m/s onto a contact
-- (touch at step 5, fraction 0.05: gap = 4.05/60 * 0.2 m). Does the contact set
-- ever report the touch? Does the circuit close, with and without ahead?
local kit = require "kit"
local AHEAD = true
local V = 0.2
local GAP = (4 + 0.05) / 60 * V
world { dt = 1/60, seconds = 0.3, use = { rigid_body = "rigid_body.box2d" },
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0.01, 0 } }
kit.bar { name = "bar", material = "brass", at = { -GAP - 0.05, 0 }, length = 0.1, width = 0.01,
          velocity = { V, 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar" }
