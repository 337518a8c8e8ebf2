-- adv21: a predicted touch that never happens. A brass bar glides at 0.3 m/s
-- toward a brass contact whose face is covered by a 0.3 mm felt pad (a static
-- insulating wall, restitution 0.05). The bar is stopped by the pad and never
-- touches the brass. Battery - bar, battery - contact wired. At the end of
-- step 1 the bar's front is 0.1 mm from the pad, 0.4 mm from the brass; moved
-- on half a step (0.625 mm) it would overlap the brass.
-- Promise (docs/electricity.md): "A predicted touch that the next update
-- neither finds nor predicts again is disconnected there (a part that bounced
-- away within the half step)".
local kit = require "kit"
local AHEAD = true
local V = 0.3
world { dt = 1/240, seconds = 0.1,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0.0103, 0 }, size = { 0.02, 0.03 } }        -- brass face at x = 0.0003
kit.wall { name = "pad", material = "felt", at = { 0.00015, 0 }, size = { 0.0003, 0.03 } } -- felt x = 0 .. 0.0003
kit.bar { name = "bar", material = "brass", at = { -0.0001 - V / 240 - 0.05, 0 }, length = 0.1, width = 0.01,
          velocity = { V, 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar" }
