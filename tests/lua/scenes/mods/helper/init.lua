-- A mod that builds on the kit: a new component, and a function that makes
-- several parts at once.
local kit = require "kit"

kit.define("lever", {
  doc = "a short steel lever",
  args = { { "at", "vec", required = true } },
  build = function(a)
    return { shape = "box", size = { 0.3, 0.02, 0.02 }, position = a.at, mass = 7850 * 0.3 * 0.02 * 0.02, planar = true }
  end,
})

local helper = {}

function helper.pendulum(name, pivot, length)
  kit.bar { name = name .. "_bar", at = { pivot[1] + length / 2, pivot[2] }, length = length }
  kit.hinge { name = name .. "_hinge", a = name .. "_bar", anchor = pivot }
end

return helper
