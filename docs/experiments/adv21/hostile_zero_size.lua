-- adv21 hostile: a conductive bar of size 1e-9 m gliding onto the contact
local kit = require "kit"
world { dt = 1/240, seconds = 0.1,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = true } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0.01, 0 } }
object { name = "bar", shape = "box", size = { 1e-9, 1e-9, 1e-9 }, mass = 0.1, conductive = true, position = { -0.02, 0, 0 }, velocity = { 1, 0, 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar", length = 0.5 }
