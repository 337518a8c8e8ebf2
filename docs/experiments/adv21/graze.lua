-- adv21: grazing. A brass bar flies at 1 m/s along x over a brass contact,
-- its bottom face GAP above the contact's top face (never touching; no gravity).
-- Any connected is a phantom.
local kit = require "kit"
local AHEAD = true
local GAP = 1e-4
local VY = 0
world { dt = 1/240, seconds = 0.3,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0, 0 } }                  -- top face at y = 0.005
kit.bar { name = "bar", material = "brass", at = { -0.15, 0.005 + GAP + 0.005 }, length = 0.1, width = 0.01,
          velocity = { 1, VY } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar", length = 0.5 }
