-- adv20: tests/coupled/scenes/magnet_through_air_coil.lua (4000 turns,
-- shorted) with the coil's `current` set to 2 A by the timeline at 0.5 s,
-- while the magnet is entering the coil.
world { dt = 1/240, seconds = 1.2,
        settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } } } }
object { name = "coil", position = {0, 0, 0},
         magnet = "electromagnet", turns = 4000, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 0.01, resistance = 3.0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil",
         wire_to_terminal = 1, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.5,
         magnet = "permanent", pole_strength = 100, pole_separation = 0.017,
         position = {-0.4, 0, 0}, velocity = {0.5, 0, 0} }
at(0.5, "coil", { current = 2 })
