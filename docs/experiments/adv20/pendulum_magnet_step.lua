-- adv20 (ODE's exact solver "step"): pendulum_coil_every2.lua with the roles swapped: a 0.2 kg magnet
-- (q = 100 A m, poles 17 mm apart) on a 0.3 m pendulum swings 1.5 cm over a
-- fixed, shapeless, shorted air coil (2000 turns) (single rate; the reference of pendulum_magnet_every2.lua).
-- Gravity on.
local L, th = 0.3, 0.6
world { dt = 1/240, seconds = 3, settings = { rigid_body = { solver = "step" } } }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.2,
         position = {L * math.sin(th), 0.3 - L * math.cos(th), 0},
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017 }
object { name = "pivot", joint = "hinge", body_a = "mag", anchor = {0, 0.3, 0}, axis = {0, 0, 1} }
object { name = "coil", position = {0, -0.015, 0}, magnet = "electromagnet", turns = 2000,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 0.01, resistance = 0.5 }
object { name = "w", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil", wire_to_terminal = 1, resistance = 0.01 }
