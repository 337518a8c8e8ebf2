-- Parts fixed to the board (a battery, a contact, a coil, a bell): static
-- scenery by default, or (pinned = true) a body of their own mass held by a
-- pin, which the scene's timeline may let go (at(t, name, { pinned = false })).
local geometry = require "kit.geometry"

local mount = {}

--- Appends the arguments every mounted part takes.
function mount.args(list)
  list[#list + 1] = { "angle", "number", default = 0, doc = "rotation about +z, rad" }
  list[#list + 1] = { "pinned", "boolean", default = false,
                      doc = "false: static scenery; true: a body of its mass pinned to the play area" }
  return list
end

--- Position and orientation, and either static = true or mass + pinned.
function mount.place(a, p, mass)
  p.position = a.at
  p.orientation = geometry.quat_z(a.angle)
  if a.pinned then
    p.mass = mass
    p.pinned = true
    p.planar = true
  else
    p.static = true
  end
  return p
end

return mount
