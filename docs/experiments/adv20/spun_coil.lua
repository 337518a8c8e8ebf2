-- adv20: tests/energy/scenes/spun_magnet.lua with the roles swapped: the
-- closed coil (500 turns, L = 1 mH, R = 3 ohm, a 1 kg box on a hinge through
-- its centre) spins at 100 rad/s next to a fixed, shapeless magnet
-- (q = 100 A m) 6 cm from it on the coil's starting axis. No gravity.
world { dt = 1 / 240, seconds = 0.5, settings = { ["gravity.uniform"] = { g = { 0, 0, 0 } },
        rigid_body = { solver = "step" } } }
object { name = "coil", shape = "box", size = {0.02, 0.01, 0.01}, mass = 1.0, planar = true,
         position = {0.06, 0, 0}, angular_velocity = {0, 0, 100},
         magnet = "electromagnet", turns = 500, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 1e-3, resistance = 3.0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil",
         wire_to_terminal = 1, resistance = 0.01 }
object { name = "axle", joint = "hinge", body_a = "coil", anchor = {0.06, 0, 0}, axis = {0, 0, 1} }
object { name = "mag", position = {0, 0, 0}, magnet = "permanent", pole_strength = 100, pole_separation = 0.017 }
