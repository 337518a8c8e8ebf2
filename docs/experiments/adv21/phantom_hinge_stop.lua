-- adv21: phantom make (phantom_hinge.py ode, phase 1): a brass bar turns at 2 rad/s about a hinge
-- onto a contact; the hinge's stop halts it 0.2 mm short. No contact is ever reported, yet with
-- ahead the circuit is closed for step 13 (connected 13, disconnected 14). Box2D: add use = { rigid_body = "rigid_body.box2d" }.
local kit = require "kit"
world { dt = 0.004166666666666667, seconds = 0.3, 
  settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
               electricity_from_collisions = { ahead = true } } }
kit.battery { name = "bat", at = { 0, 0.5 } }
kit.bar { name = "bar", material = "brass", at = { 0.05, 0 }, length = 0.1, width = 0.01,
          velocity = { 0, -0.1 }, spin = -2.0, props = { restitution = 0 } }
kit.hinge { name = "h", a = "bar", anchor = { 0, 0 }, limits = { -0.09881944444444445, 1 } }
kit.contact { name = "c", at = { 0.08, -0.01915045677943199 }, size = { 0.02, 0.01 }, props = { restitution = 0 } }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "c" }
kit.wire { name = "w0", from = "bat", from_terminal = 0, to = "bar" }
