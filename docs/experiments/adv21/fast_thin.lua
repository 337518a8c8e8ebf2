-- adv21: the prediction samples one pose (half a step on), not the path. A
-- brass disk (radius 2 mm) at 3 m/s meets a brass contact 1 mm thick; at
-- 1/240 s it moves 6.25 mm in half a step, more than the 5 mm over which the
-- two overlap, so a touch early in a step (fraction F) is not predicted: the
-- half-step pose lies past the contact. The engines stop the disk at the
-- contact (ccd on ODE, TOI on Box2D). Promise: "connected at the step boundary
-- nearest to it ... never more [than half a step late]".
local kit = require "kit"
local AHEAD = true
local F = 0.1
local V = 3
local GAP = (4 + F) / 240 * V
world { dt = 1/240, seconds = 0.05,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.contact { name = "c", at = { 0.0005, 0 }, size = { 0.001, 0.02 } }  -- x = 0 .. 0.001
kit.disk { name = "d", material = "brass", at = { -GAP - 0.002, 0 }, radius = 0.002, velocity = { V, 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "d" }
