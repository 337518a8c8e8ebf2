-- adv20: an air coil in no circuit (no wires; it has inductance and
-- resistance) whose `current` the scene sets to 2 A; a 0.5 kg magnet is flown
-- through it at 0.5 m/s. No gravity.
world { dt = 1/240, seconds = 1.2,
        settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "coil", position = {0, 0, 0}, current = 2,
         magnet = "electromagnet", turns = 4000, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 0.01, resistance = 3.0 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.5,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
