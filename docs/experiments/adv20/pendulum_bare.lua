-- adv20 (outside the feature): a 0.2 kg box (2 x 1 x 1 cm) on a 0.3 m hinge,
-- released 0.6 rad out, nothing else; ODE's default solver (QuickStep).
-- Its angular_velocity.z jumps about (compare rigid_body = { solver = "step" }).
local L, th = 0.3, 0.6
world { dt = 1/240, seconds = 1 }
object { name = "bob", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.2,
         position = {L * math.sin(th), 0.3 - L * math.cos(th), 0} }
object { name = "pivot", joint = "hinge", body_a = "bob", anchor = {0, 0.3, 0}, axis = {0, 0, 1} }
