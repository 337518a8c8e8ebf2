-- adv21: conductive toggled while approaching. A brass bar (0.1 x 0.03) glides
-- at 0.2 m/s onto two contacts stacked above each other (faces at x = 0),
-- bridging them; the battery is wired to the two contacts. Touch inside step 5
-- at fraction 0.3 (1/240 s). The bar is made non-conductive at T_OFF and
-- conductive again at T_ON (edited by the driver).
local kit = require "kit"
local AHEAD = true
local T_OFF, T_ON = 4 / 240, 0.05
local V = 0.2
local GAP = (4 + 0.3) / 240 * V
world { dt = 1/240, seconds = 0.1,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c1", at = { 0.01, 0.008 } }
kit.contact { name = "c2", at = { 0.01, -0.008 } }
kit.bar { name = "bar", material = "brass", at = { -GAP - 0.05, 0 }, length = 0.1, width = 0.03,
          velocity = { V, 0 }, props = { restitution = 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c1" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "c2" }
at(T_OFF, "bar", { conductive = false })
at(T_ON, "bar", { conductive = true })
