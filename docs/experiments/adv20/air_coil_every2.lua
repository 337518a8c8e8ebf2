-- adv20: tests/coupled/scenes/magnet_through_air_coil.lua with the rigid body every 2nd step.
-- The induction work-precision scene (tests/scenes/analytic_scenes.cpp
-- run_induction) as a scene file: a 0.5 kg magnet (20 x 10 x 10 mm, q = 100
-- A m) flown at 0.5 m/s along the axis of a fixed air-cored coil (4000
-- turns, coil_factor 0.06 m, poles 4 cm apart: a current sheet of radius
-- 2.76 cm, L = 10 mH) shorted by a 0.01 ohm wire, from 0.4 m before its
-- centre and through it; no gravity. bench/near_field_cost.sh times it with
-- magnetic_forces' near_field on (the default) and off.
world { dt = 1/240, seconds = 1.2, every = { rigid_body = 2 },
        settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
                     electricity = { induction_order = 2 } } }
object { name = "coil", position = {0, 0, 0},
         magnet = "electromagnet", turns = 4000, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 0.01, resistance = 3.0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil",
         wire_to_terminal = 1, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.5,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
