-- adv20: a 15 g magnet (q = 100 A m, north down) dropped from 8 cm above the
-- centre of a fixed, shapeless 500-turn air coil (coil_factor 0.06 m, poles
-- 4 cm apart, L = 1 mH, R = 3 ohm) closed by a 0.01 ohm wire: the scene of
-- tests/coupled/scenes/drop_into_coil.lua with the near field on (the
-- default), falling right through the coil. Gravity on.
world { dt = 1/240, seconds = 0.5 }
object { name = "coil", position = {0, 0, 0},
         orientation = {0.7071067811865476, 0, 0, 0.7071067811865476},
         magnet = "electromagnet", turns = 500, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 1e-3, resistance = 3.0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil",
         wire_to_terminal = 1, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.015, planar = true,
         magnet = "permanent", pole_strength = 100, position = {0, 0.08, 0},
         orientation = {0.7071067811865476, 0, 0, -0.7071067811865476} }
