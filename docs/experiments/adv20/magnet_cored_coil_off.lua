-- adv20 (magnet_no_iron.lua, the switch open throughout: no current): a kit coil (iron core, 500 turns) on a kit battery through a switch
-- toggled every 0.1 s; a soft-iron armature hung on a hinge 1 cm beyond the
-- coil's +x face, and a neodymium bar magnet swinging on a hinge beyond the
-- -x face. Gravity on (the hinges hang the parts).
local kit = require "kit"
world { dt = 1 / 240, seconds = 3 }
kit.coil { name = "coil", at = { 0, 0 } }
kit.battery { name = "bat", at = { 0, -0.2 } }
kit.switch { name = "sw", at = { 0.15, -0.2 }, closed = false }
kit.wire { name = "w1", from = "bat", from_terminal = 1, to = "sw", to_terminal = 0 }
kit.wire { name = "w2", from = "sw", from_terminal = 1, to = "coil", to_terminal = 1 }
kit.wire { name = "w3", from = "coil", from_terminal = 0, to = "bat", to_terminal = 0 }
kit.magnet { name = "mag", at = { -0.025 - 0.012 - 0.025, 0.0 } }
kit.hinge { name = "h2", a = "mag", anchor = { -0.062, 0.08 } }
local closed = true
for k = 1, 0 do
  closed = not closed
  at(k * 0.1, "sw", { switch_closed = closed })
end
