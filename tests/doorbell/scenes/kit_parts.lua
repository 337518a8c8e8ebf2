-- One of each electrical, magnetic and acoustic kit part, with values the
-- tests check by hand (tests/doorbell/kit_parts_test.cpp).
local kit = require "kit"

world { seconds = 1 }

kit.battery { name = "battery", at = { 0, 0 } }
kit.battery { name = "pack", at = { 0, 0.2 }, emf = 12, internal_resistance = 0.8, pinned = true }
kit.contact { name = "contact", at = { 0.3, 0 } }
kit.contact { name = "pinned_contact", at = { 0.3, 0.1 }, material = "copper", pinned = true }
kit.wire { name = "lead", from = "battery", from_terminal = 1, to = "contact" }
kit.wire { name = "long_lead", from = "contact", to = "battery", length = 2, diameter = 1e-3 }
kit.coil { name = "coil", at = { 0.6, 0 } }
kit.coil { name = "air_coil", at = { 0.6, 0.2 }, core = "air", turns = 200 }
kit.magnet { name = "magnet", at = { 0.9, 0 } }
kit.magnet { name = "ferrite", at = { 0.9, 0.2 }, grade = "ferrite", north = "-x" }
kit.armature { name = "armature", at = { 1.2, 0 }, length = 0.03 }
kit.bar { name = "iron_bar", material = "iron", at = { 1.2, 0.2 }, length = 0.1 }
kit.bar { name = "steel_bar", material = "steel", at = { 1.2, 0.4 }, length = 0.1 }
kit.bar { name = "magnetic_steel", material = "steel", at = { 1.2, 0.6 }, length = 0.1, magnetic = true }
kit.bar { name = "wooden_bar", material = "wood", at = { 1.2, 0.8 }, length = 0.1 }
kit.bell { name = "bell", at = { 1.5, 0 } }
kit.bell { name = "tuned_bell", at = { 1.5, 0.2 }, radius = 0.05, pitch = 1200, decay = 2, pinned = true }
