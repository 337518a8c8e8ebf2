-- adv21: areas. Everything inside the area "right" (x >= 0, Box2D): a brass
-- bar glides at 0.2 m/s onto a contact, the battery beside them. Does the
-- circuit close (ahead on and off)?
local kit = require "kit"
local AHEAD = true
world { dt = 1/240, seconds = 0.2,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } },
  areas = {
    { name = "right", center = { 1, 0, 0 }, half_extents = { 1, 1, 1 },
      plugins = { "rigid_body.box2d", "collisions.box2d", "rigid_body_from_gravity" } },
  } }
kit.battery { name = "bat", at = { 1, 0.5 } }
kit.contact { name = "c", at = { 1.01, 0 } }
local GAP = (4 + 0.3) / 240 * 0.2
kit.bar { name = "bar", material = "brass", at = { 1 - GAP - 0.05, 0 }, length = 0.1, width = 0.01,
          velocity = { 0.2, 0 }, props = { restitution = 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar" }
