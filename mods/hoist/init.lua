-- A string, for scenes: one end wound on a drum (a part that turns: an
-- axle), the other tied to a part (a load). What it does is in runtime.lua:
-- the drum turning anticlockwise takes string in, the string pulls on both
-- ends with its elastic tension, and it goes slack rather than push.
--
--   local hoist = require "hoist"
--   hoist.string { name = "line", drum = "axle", radius = 0.005, load = "weight", length = 0.3 }
local kit = require "kit"

local string_part = kit.define("string", {
  doc = "a string wound on a drum (turning anticlockwise winds it in) and tied to a load",
  args = {
    { "drum", "object", required = true, doc = "the part it is wound on; it winds about that part's centre" },
    { "radius", "positive", required = true, doc = "of the drum where the string lies, m" },
    { "load", "object", required = true, doc = "the part tied to its free end (at its centre)" },
    { "length", "positive", required = true, doc = "free length, unstretched, from the drum to the load at the start, m" },
    -- Nylon monofilament of 0.4 mm (a fishing line): E about 2.4 GPa on
    -- 0.126 mm^2, EA about 300 N; 100 g stretches it by 0.3 %.
    { "stiffness", "positive", default = 300, doc = "EA: tension per unit strain, N" },
    -- Its internal friction: tension from the strain rate, enough to settle
    -- a bounce within a few periods. The string pulls through forces queued
    -- once a step (explicit): stable while sqrt(EA / (L m)) dt stays well
    -- below 2 (L the free length, m the load); with these values, 20 g on
    -- 0.45 m at 1/240 s: 0.76.
    { "damping", "nonnegative", default = 0.5, doc = "tension per unit strain rate, N s" },
  },
  build = function(a)
    return {
      string_drum = a.drum,
      string_load = a.load,
      string_radius = a.radius,
      string_free_length = a.length,
      string_stiffness = a.stiffness,
      string_damping = a.damping,
    }
  end,
})

return { string = string_part }
