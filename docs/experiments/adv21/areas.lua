-- adv21: areas. The area "right" (x >= 0) runs Box2D; the rest of the world
-- ODE. A static brass contact whose centre is in the area (so it exists only
-- for Box2D's bodies) has its face at x = 0.0; a brass bar on ODE (centre at
-- x < 0) glides at 0.2 m/s toward it. Bodies on two engines do not touch
-- (docs/architecture.md, "Not across engines"): the bar passes into the
-- contact until its centre crosses x = 0. What does ahead connect?
local kit = require "kit"
local AHEAD = true
world { dt = 1/240, seconds = 0.4,
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = AHEAD } },
  areas = {
    { name = "right", center = { 1, 0, 0 }, half_extents = { 1, 1, 1 },
      plugins = { "rigid_body.box2d", "collisions.box2d", "rigid_body_from_gravity", "electricity_from_collisions" } },
  } }
kit.battery { name = "bat", at = { -0.5, 0.5 } }
kit.contact { name = "c", at = { 0.01, 0 } }
kit.bar { name = "bar", material = "brass", at = { -0.06, 0 }, length = 0.1, width = 0.01,
          velocity = { 0.2, 0 }, props = { restitution = 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar" }
