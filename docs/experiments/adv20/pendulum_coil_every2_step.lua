-- adv20 (ODE's exact solver "step") (the rigid body every 2nd step): an air coil (a 0.2 kg box 4 x 2 x 2 cm, 2000 turns, coil_factor
-- 0.06 m, poles 4 cm apart) on a 0.3 m pendulum, shorted by a wire, swings
-- over a fixed, shapeless permanent magnet 1.5 cm below its lowest point (inside the sheet's radius).
-- Released 0.6 rad out. Gravity on.
local L, th = 0.3, 0.6
world { dt = 1/240, seconds = 3, settings = { rigid_body = { solver = "step" } }, every = { rigid_body = 2 } }
object { name = "coil", shape = "box", size = {0.04, 0.02, 0.02}, mass = 0.2,
         position = {L * math.sin(th), 0.3 - L * math.cos(th), 0},
         magnet = "electromagnet", turns = 2000, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 0.01, resistance = 0.5 }
object { name = "pivot", joint = "hinge", body_a = "coil", anchor = {0, 0.3, 0}, axis = {0, 0, 1} }
object { name = "w", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil", wire_to_terminal = 1, resistance = 0.01 }
object { name = "mag", position = {0, -0.015, 0}, magnet = "permanent", pole_strength = 100, pole_separation = 0.017 }
