-- The magnet of drop_into_coil.lua (15 g, q = 100 A m, north down, 8 cm
-- above the centre) dropped into the same 500-turn coil left open (no
-- wire): no current flows, nothing brakes the magnet, and there is no
-- strong coupling to report.
world { dt = 1/240, seconds = 0.3 }
object { name = "coil", position = {0, 0, 0},
         orientation = {0.7071067811865476, 0, 0, 0.7071067811865476},
         magnet = "electromagnet", turns = 500, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 1e-3, resistance = 3.0 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.015, planar = true,
         magnet = "permanent", pole_strength = 100, position = {0, 0.08, 0},
         orientation = {0.7071067811865476, 0, 0, -0.7071067811865476} }
