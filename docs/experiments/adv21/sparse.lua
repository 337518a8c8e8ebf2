-- adv21 cost: N brass disks far apart on a grid (no gravity, at rest, no pair's
-- bounds overlap), one battery wired to two of them. With ahead no pair needs
-- testing; does the interaction's cost still grow with N?
local kit = require "kit"
local N = 1600
local AHEAD = true
world { dt = 1/240, seconds = 1,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
local side = math.ceil(math.sqrt(N))
for i = 0, N - 1 do
  kit.disk { name = "d" .. i, material = "brass", radius = 0.01,
             at = { (i % side) * 0.1, math.floor(i / side) * 0.1 } }
end
kit.battery { name = "bat", at = { -1, -1 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "d0", length = 3 }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "d" .. (N - 1), length = 3 }
