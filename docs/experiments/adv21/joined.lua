-- adv21: joined parts never touch. Two brass bars glued end to end (touching,
-- 0.1 mm overlap) fly at 1 m/s and spin at 3 rad/s; two brass bars hinged at
-- a shared end (overlapping there) swing; two static brass contacts overlap.
-- Each pair is wired across a battery of its own: any `connected` is wrong.
local kit = require "kit"
local AHEAD = true
world { dt = 1/240, seconds = 0.5,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
kit.bar { name = "g1", material = "brass", at = { -0.05, 0 }, length = 0.1, width = 0.01, velocity = { 1, 0.2 }, spin = 3 }
kit.bar { name = "g2", material = "brass", at = { 0.0499, 0 }, length = 0.1, width = 0.01, velocity = { 1, 0.5 }, spin = 3 }
kit.glue { name = "glue", a = "g1", b = "g2" }
kit.bar { name = "h1", material = "brass", at = { -0.05, 1 }, length = 0.1, width = 0.01, spin = 5 }
kit.bar { name = "h2", material = "brass", at = { 0.045, 1 }, length = 0.1, width = 0.01, spin = -5 }
kit.hinge { name = "hinge", a = "h1", b = "h2", anchor = { -0.003, 1 } }
kit.contact { name = "s1", at = { 0, -1 } }
kit.contact { name = "s2", at = { 0.015, -1 } }
for i, p in ipairs({ { "g1", "g2" }, { "h1", "h2" }, { "s1", "s2" } }) do
  kit.battery { name = "bat" .. i, at = { 2, i } }
  kit.wire { name = "wa" .. i, from = "bat" .. i, from_terminal = 1, to = p[1], length = 3 }
  kit.wire { name = "wb" .. i, from = "bat" .. i, from_terminal = 0, to = p[2], length = 3 }
end
