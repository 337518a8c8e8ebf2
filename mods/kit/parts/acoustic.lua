-- Parts of the kit that ring: the bell. The sound resolver (docs/sound.md)
-- synthesises a struck part from its family of modes, its pitch and its
-- decay; these come from the part's size and material unless given.
local mount = require "kit.mount"

local acoustic = {}

acoustic.bell = {
  doc = "a bell (a gong, seen edge on in the play area as a disk): it rings at its pitch when struck",
  args = mount.args({
    { "material", "material", default = "bronze" },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "radius", "positive", default = 0.03, doc = "m" },
    { "pitch", "positive", doc = "Hz, the prime; default: from the size and the material (a flat-plate estimate, good to a factor of two)" },
    { "decay", "positive", doc = "s, T60 of the prime; default: from the material's loss factor" },
    { "loudness", "nonnegative", doc = "gain of its sound (default 1)" },
  }),
  build = function(a)
    local m = a.material
    if not m.youngs_modulus then
      error("a bell needs a material with a youngs_modulus ('" .. (m.name or "this material") .. "' has none)", 0)
    end
    local r = a.radius
    local p = {
      shape = "sphere",
      radius = r,
      acoustic = "bell",
      youngs_modulus = m.youngs_modulus,
      loss_factor = m.loss_factor,
      pitch = a.pitch,
      decay = a.decay,
      loudness = a.loudness,
      friction = m.friction,
      restitution = m.restitution,
      conductive = m.conductive or nil,
    }
    -- The metal's density: the sound resolver computes the pitch from it, and
    -- a pinned bell weighs what a solid dome of it would (its mass decides
    -- how much a blow shakes it: sound's strike speed is J / m).
    p.density = m.density
    return mount.place(a, p, m.density * 4 / 3 * math.pi * r ^ 3)
  end,
}

-- The kit's own: other mods use these parts through `require "kit"`.
return alloy.per_mod(function(mod)
  if mod == "kit" then return acoustic end
end)
