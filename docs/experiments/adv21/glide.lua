-- adv21: a brass bar glides at constant speed (no gravity, no friction with
-- anything) onto a brass contact; battery - bar, battery - contact wired.
-- The bar's front face is at x = -GAP at t = 0, the contact's face at 0.
local kit = require "kit"
local GAP = 0.0123   -- m
local V = 1.0        -- m/s
world { dt = 1/240, seconds = 0.05,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = true } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0.01, 0 } }            -- faces at x = 0 .. 0.02
kit.bar { name = "bar", material = "brass", at = { -GAP - 0.05, 0 }, length = 0.1, width = 0.01,
          velocity = { V, 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar" }
