-- adv21 cost: N brass disks dropped into a wooden box, resting in a pile
-- (all conductive, all touching their neighbours), one battery wired to two
-- of them so that the electricity resolver and electricity_from_collisions run.
-- N and AHEAD are edited by cost.sh.
local kit = require "kit"
local N = 400
local AHEAD = true
world { dt = 1/240, seconds = 4,
  settings = { ["gravity.uniform"] = { g = { 0, -9.81, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
local W = 1.0
kit.floor { name = "floor", at = { 0, -0.05 }, size = { W + 0.2, 0.1 } }
kit.wall { name = "left", at = { -W / 2 - 0.05, 1 }, size = { 0.1, 2 } }
kit.wall { name = "right", at = { W / 2 + 0.05, 1 }, size = { 0.1, 2 } }
local r = 0.012
local per_row = math.floor(W / (2.2 * r))
for i = 0, N - 1 do
  local row, col = math.floor(i / per_row), i % per_row
  kit.disk { name = "d" .. i, material = "brass", radius = r,
             at = { -W / 2 + 1.1 * r + col * 2.2 * r + (row % 2) * 0.3 * r, r + row * 2.3 * r } }
end
kit.battery { name = "bat", at = { 0, 3 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "d0", length = 3 }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "d" .. (N - 1), length = 3 }
