-- adv20 hostile: a 0.5 kg magnet flown at 0.5 m/s through a shorted air coil
-- with turns = 100, inductance = 0 H, resistance = 0 ohm, wire 0 ohm,
-- coil_factor 0.06 m. No gravity.
world { dt = 1/240, seconds = 1.2, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "coil", position = {0, 0, 0}, magnet = "electromagnet", turns = 100, coil_factor = 0.06,
         pole_separation = 0.04, inductance = 0, resistance = 0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil", wire_to_terminal = 1, resistance = 0 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.5, magnet = "permanent",
         pole_strength = 100, pole_separation = 0.017, position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
