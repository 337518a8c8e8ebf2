-- adv20: an air coil in series with a 1 mF capacitor (no battery, a closed LC
-- loop, f0 = 1/(2 pi sqrt(LC)) = 50 Hz) and a 0.1 kg magnet flown at 0.5 m/s
-- through the coil. No gravity.
world { dt = 1/240, seconds = 1.2, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "a", position = {0, 0, 0}, magnet = "electromagnet", turns = 4000,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 0.01, resistance = 1.0 }
object { name = "c", capacitance = 1e-3, resistance = 0.01 }
object { name = "w1", wire_from = "a", wire_from_terminal = 1, wire_to = "c", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w2", wire_from = "c", wire_from_terminal = 1, wire_to = "a", wire_to_terminal = 0, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.1,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
