-- The kit's resistor, capacitor and switch in one loop: battery + -> switch
-- -> resistor -> capacitor -> battery - (tests/doorbell/kit_parts_test.cpp).
local kit = require "kit"

world { seconds = 1 }

kit.battery { name = "battery", at = { 0, 0 } }
kit.switch { name = "switch", at = { 0.2, 0 } }
kit.resistor { name = "resistor", at = { 0.4, 0 }, resistance = 100 }
kit.capacitor { name = "capacitor", at = { 0.6, 0 }, capacitance = 1e-3, charge = 1e-3, pinned = true }
kit.switch { name = "closed_switch", at = { 0.8, 0 }, closed = true, resistance = 0.01 }
kit.wire { name = "w1", from = "battery", from_terminal = 1, to = "switch" }
kit.wire { name = "w2", from = "switch", from_terminal = 1, to = "resistor" }
kit.wire { name = "w3", from = "resistor", from_terminal = 1, to = "capacitor" }
kit.wire { name = "w4", from = "capacitor", from_terminal = 1, to = "battery" }
