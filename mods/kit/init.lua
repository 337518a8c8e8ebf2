-- The kit's public face:
--
--   local kit = require "kit"
--   kit.bar   { name = "arm", material = "steel", at = {1, 2}, length = 1, width = 0.05, angle = 0 }
--   kit.disk  { name = "ball", material = "rubber", at = {0.5, 3}, radius = 0.1 }
--   kit.floor { name = "floor", at = {0, 0}, size = {4, 0.1} }
--   kit.hinge { name = "pivot", a = "arm", anchor = {0.5, 2} }   -- b absent: the play area
--   kit.pin   { name = "axle", part = "wheel" }
--   kit.glue  { a = "arm", b = "ball" }
--
-- Mods grow the kit with kit.define (new components) and kit.add_material.
-- Every part takes `name` and `props` (raw property overrides, e.g.
-- props = { linear_damping = 0.1 }) and returns its name.
local registry = require "kit.registry"
local materials = require "kit.materials"

for name, m in pairs(materials) do registry.add_material(name, m) end
for _, group in ipairs({ require "kit.parts.bodies", require "kit.parts.joints", require "kit.parts.electric",
                         require "kit.parts.magnetic", require "kit.parts.acoustic" }) do
  for name, spec in pairs(group) do registry.define(name, spec) end
end

local kit = {
  define = registry.define,           -- kit.define(name, { doc, args, build })
  add_material = registry.add_material,
  material = registry.material,       -- kit.material("steel") -> { density, friction, restitution }
  materials = registry.material_names,  -- sorted names
  parts = registry.names,             -- sorted component names
  component = registry.component,     -- the spec of a component, for docs and tools
  placed = registry.placed,
}

-- kit.<part> finds the component at call time, so parts defined later by
-- other mods are there too, and an unknown one is reported with a suggestion.
setmetatable(kit, {
  __index = function(_, part)
    local c = registry.component(part)
    return c and c.make or registry.unknown(part)
  end,
})

return alloy.freeze(kit)
