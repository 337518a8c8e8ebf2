-- A magnet dropped into a closed coil (the shape of adversary adv13's F2,
-- docs/energy.md "Limits"): a 15 g NdFeB-like magnet (q = 100 A m, 20x10x10
-- mm), north down, released 8 cm above the centre of a fixed 500-turn coil
-- (coil_factor 0.06 m, poles 4 cm apart, L = 1 mH, R = 3 ohm) that a
-- 0.01 ohm wire closes. Near the coil the eddy braking rate G^2/(m R) is
-- 340 to 870 1/s: at the default step the one-step-late coupling
-- overshoots. drop_into_open_coil.lua: the same with no wire.
-- The coil is its pole pair, as adv13 found F2 (near_field = false): that
-- pair's near field gives G up to 6.3 Wb/m inside the coil. As a current
-- sheet (magnetic_forces' default since session 20) G is at most 0.376
-- Wb/m and this coupling is never strong; the detector under test does not
-- depend on which flux the coupling has.
world { dt = 1/240, seconds = 0.3,
        settings = { magnetic_forces = { near_field = false } } }
object { name = "coil", position = {0, 0, 0},
         orientation = {0.7071067811865476, 0, 0, 0.7071067811865476},
         magnet = "electromagnet", turns = 500, coil_factor = 0.06, pole_separation = 0.04,
         inductance = 1e-3, resistance = 3.0 }
object { name = "wire", wire_from = "coil", wire_from_terminal = 0, wire_to = "coil",
         wire_to_terminal = 1, resistance = 0.01 }
object { name = "mag", shape = "box", size = {0.02, 0.01, 0.01}, mass = 0.015, planar = true,
         magnet = "permanent", pole_strength = 100, position = {0, 0.08, 0},
         orientation = {0.7071067811865476, 0, 0, -0.7071067811865476} }
