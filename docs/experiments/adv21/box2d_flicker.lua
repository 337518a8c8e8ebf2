-- adv21: Box2D flicker. A brass disk (radius 2 mm) at 3 m/s hits a brass
-- contact 1 mm thick and bounces off (touch inside step 5 at fraction 0.3,
-- 1/240 s). With ahead: connected at 5 (predicted), disconnected at 6 (the
-- set has not reported it yet and the disk is leaving), contact began at 6
-- (Box2D reports a step late), connected again at 7, disconnected at 8: one
-- touch, two makes and two breaks. Without ahead: one make (7), one break (8).
-- (fast_thin.lua on Box2D.)
local kit = require "kit"
local AHEAD = true
local F = 0.3
local V = 3
local GAP = (4 + F) / 240 * V
world { dt = 1/240, seconds = 0.05, use = { rigid_body = "rigid_body.box2d" },
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0.0005, 0 }, size = { 0.001, 0.02 } }  -- x = 0 .. 0.001
kit.disk { name = "d", material = "brass", at = { -GAP - 0.002, 0 }, radius = 0.002, velocity = { V, 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "d" }
