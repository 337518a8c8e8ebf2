-- adv20: a 0.1 kg magnet (north +x, along the axis) released at rest at the
-- centre of a powered, shapeless air coil whose axis is horizontal (x): 2000
-- turns on 6 V, coil_factor 0.06 m, poles 4 cm apart (a current sheet of
-- radius 2.76 cm). Gravity (-y) pulls the magnet down, across the winding.
world { dt = 1/240, seconds = 0.5 }
object { name = "a", position = {0, 0, 0}, magnet = "electromagnet", turns = 2000,
         coil_factor = 0.06, pole_separation = 0.04, inductance = 0.01, resistance = 3.0 }
object { name = "bat", emf = 6, internal_resistance = 0.5 }
object { name = "w1", wire_from = "bat", wire_from_terminal = 1, wire_to = "a", wire_to_terminal = 0, resistance = 0.01 }
object { name = "w2", wire_from = "a", wire_from_terminal = 1, wire_to = "bat", wire_to_terminal = 0, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.1,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {0, 0, 0} }
