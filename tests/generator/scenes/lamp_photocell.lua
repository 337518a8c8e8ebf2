-- The kit's lamp and photocell (tests/generator/generator_test.cpp): a 6 V
-- battery lights the lamp; a photocell 10 cm below it, face up, sits in a
-- second circuit of its own with a 5 V battery.
world { name = "lamp_photocell", dt = 1 / 240, seconds = 1 }
local kit = require "kit"
kit.battery { name = "battery", at = { -0.3, 0.3 } }
kit.lamp { name = "lamp", at = { 0, 0.2 } }
kit.wire { name = "w1", from = "battery", from_terminal = 1, to = "lamp", to_terminal = 0 }
kit.wire { name = "w2", from = "lamp", from_terminal = 1, to = "battery", to_terminal = 0 }
kit.battery { name = "sense", at = { 0.3, 0 }, emf = 5 }
kit.photocell { name = "cell", at = { 0, 0.1 } }
kit.wire { name = "w3", from = "sense", from_terminal = 1, to = "cell", to_terminal = 0 }
kit.wire { name = "w4", from = "cell", from_terminal = 1, to = "sense", to_terminal = 0 }
