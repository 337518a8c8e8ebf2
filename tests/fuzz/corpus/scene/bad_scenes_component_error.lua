-- expect: line 8: object 'l1': attempt to perform arithmetic on global 'lever_density' (a nil value)
-- A scene's own component with a bug: reported at the buggy line, for the object being made.
local kit = require "kit"

kit.define("lever", {
  args = { { "at", "vec", required = true }, { "length", "positive", default = 0.3 } },
  build = function(a)
    local mass = lever_density * a.length
    return { shape = "box", size = { a.length, 0.02, 0.02 }, position = a.at, mass = mass }
  end,
})

kit.lever { name = "l1", at = { 0, 1 } }
