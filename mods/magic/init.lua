-- The parts of the magic mod, for scenes: rune stones are slabs of granite
-- with a rune carved in them.
--
--   local magic = require "magic"
--   magic.stone { name = "altar", rune = "source", at = {0, 0.04}, fixed = true }
--   magic.stone { name = "feather", rune = "lift", at = {0, 0.12} }
--
-- rune = "source" makes mana, "conduit" passes it on, "lift" spends it to
-- float. The properties they carry (rune, mana, mana_capacity) are defined by
-- runtime.lua, which the world runs.
local kit = require "kit"

kit.add_material("granite", { density = 2700, friction = 0.7, restitution = 0.05 })

local runes = { source = true, conduit = true, lift = true }

local stone = kit.define("rune_stone", {
  doc = "a granite slab carved with a rune: source, conduit or lift",
  args = {
    { "rune", "string", required = true, doc = "source, conduit or lift" },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "size", "extent", default = { 0.2, 0.08 }, doc = "{width, height}, m" },
    { "depth", "positive", default = 0.08, doc = "out of the plane, m" },
    { "material", "material", default = "granite" },
    { "mana", "nonnegative", default = 0, doc = "mana at the start" },
    { "capacity", "positive", default = 1, doc = "mana it holds when full" },
    { "fixed", "boolean", default = false, doc = "static: set into the ground" },
  },
  build = function(a)
    if not runes[a.rune] then
      error("a rune stone's rune is source, conduit or lift, not '" .. a.rune .. "'", 0)
    end
    local size = { a.size[1], a.size[2], a.depth }
    local p = {
      shape = "box",
      size = size,
      position = a.at,
      friction = a.material.friction,
      restitution = a.material.restitution,
      rune = a.rune,
      mana = math.min(a.mana, a.capacity),
      mana_capacity = a.capacity,
    }
    if a.fixed then
      p.static = true
    else
      p.mass = a.material.density * size[1] * size[2] * size[3]
      p.planar = true
    end
    return p
  end,
})

-- The kit's own function, so that a stone is located at the scene line that made it.
return { stone = stone }
