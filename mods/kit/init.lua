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

for name, m in pairs(materials) do registry.add_material("kit", name, m) end
for _, group in ipairs({ require "kit.parts.bodies", require "kit.parts.joints", require "kit.parts.electric",
                         require "kit.parts.magnetic", require "kit.parts.acoustic" }) do
  for name, spec in pairs(group) do registry.define("kit", name, spec) end
end

-- The kit a mod gets: `mod` is the requiring mod's name as the host gave it
-- ("" for a loose scene), so what it defines is its own, and it cannot
-- replace another's part or material (registry.lua). Each mod's kit is
-- read-only, and shares the one registry: parts and materials any mod
-- defined are there for every scene.
local function kit_for(mod)
  local kit = {
    define = function(part, spec)  -- kit.define(name, { doc, args, build })
      local make = registry.define(mod, part, spec)
      return make
    end,
    add_material = function(name, m)
      registry.add_material(mod, name, m)
    end,
    material = registry.material,       -- kit.material("steel") -> { density, friction, restitution } (read-only)
    materials = registry.material_names,  -- sorted names
    parts = registry.names,             -- sorted component names
    component = registry.component,     -- a copy of a component's description, for docs and tools
    placed = registry.placed,
  }
  -- kit.<part> finds the component at call time, so parts defined later by
  -- other mods are there too, and an unknown one is reported with a suggestion.
  setmetatable(kit, {
    __index = function(_, part)
      return registry.maker(part) or registry.unknown(part)
    end,
  })
  return alloy.freeze(kit)
end

return alloy.per_mod(kit_for)
