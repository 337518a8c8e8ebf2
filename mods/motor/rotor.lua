-- The motor's rotor, shared by every scene built on it (mods/motor,
-- mods/generator, mods/hoist through motor.layout): eight 50 x 10 x 10 mm
-- NdFeB bar magnets lying along their radius, north out and south out in
-- turn, glued to a wooden hub pinned to the play area by a bearing with dry
-- friction and an oil's viscous drag.
--
--   require "motor.rotor" (o, extra_inertia)
--
-- o holds centre, spoke_length, spoke_width, spoke_inner, hub_radius,
-- rotor_angle (degrees, default 0), spoke_restitution (nil: the kit's),
-- axle_friction (N m) and bearing_drag (N m s). extra_inertia (kg m^2) is
-- what the scene glues on besides (a crank): the drag is a rate on the
-- rigid body (dw/dt = -c w), so c = bearing_drag / (the whole rotor's I).
-- o.commutator_z (nil: none) adds a second ring of contacts glued to the
-- axle: eight brass bars of the spokes' size and radii, commutator_z out of
-- the spokes' plane (so they touch nothing there) and turned by
-- commutator_offset degrees from the spokes, named segment_n1.. / segment_s1..
-- after the spoke they follow.
-- Returns the spokes ({ name, north }, S1 N1 S2 N2 ... from the bottom,
-- anticlockwise), the rotor's moment of inertia about the axle, and the
-- segments (as the spokes, or an empty list).
local kit = require "kit"

return function(o, extra_inertia)
  local C = o.centre
  local rad = math.rad
  local function at(r, degrees)
    return { C[1] + r * math.cos(rad(degrees)), C[2] + r * math.sin(rad(degrees)) }
  end
  -- Spoke i stands at -90 + 45 i degrees, south out for even i.
  local hub_mass = kit.material("wood").density * 4 / 3 * math.pi * o.hub_radius ^ 3
  local inertia = 2 / 5 * hub_mass * o.hub_radius ^ 2
  local spokes, counts = {}, { N = 0, S = 0 }
  local magnet_density = 7500  -- sintered NdFeB (kit.magnet's "neodymium")
  for i = 0, 7 do
    local pole = i % 2 == 1 and "N" or "S"
    counts[pole] = counts[pole] + 1
    local name = "spoke_" .. pole .. counts[pole]
    local r = o.spoke_inner + o.spoke_length / 2
    local angle = -90 + 45 * i + (o.rotor_angle or 0)
    kit.magnet { name = name, at = at(r, angle), angle = rad(angle), length = o.spoke_length,
                 width = o.spoke_width, north = pole == "N" and "+x" or "-x",
                 props = o.spoke_restitution and { restitution = o.spoke_restitution } or nil }
    kit.glue { name = name .. "_glue", a = "axle", b = name }
    spokes[#spokes + 1] = { name = name, north = pole == "N" }
    local m = magnet_density * o.spoke_length * o.spoke_width * o.spoke_width
    inertia = inertia + m * ((o.spoke_length ^ 2 + o.spoke_width ^ 2) / 12 + r * r)
  end
  local segments = {}
  if o.commutator_z then
    local brass = kit.material("brass")
    counts = { n = 0, s = 0 }
    for i = 0, 7 do
      local pole = i % 2 == 1 and "n" or "s"
      counts[pole] = counts[pole] + 1
      local name = "segment_" .. pole .. counts[pole]
      local r = o.spoke_inner + o.spoke_length / 2
      local angle = -90 + 45 * i + (o.rotor_angle or 0) + o.commutator_offset
      local p = at(r, angle)
      kit.bar { name = name, material = "brass", at = { p[1], p[2], o.commutator_z }, angle = rad(angle),
                length = o.spoke_length, width = o.spoke_width, depth = o.commutator_depth,
                props = o.spoke_restitution and { restitution = o.spoke_restitution } or nil }
      kit.glue { name = name .. "_glue", a = "axle", b = name }
      segments[#segments + 1] = { name = name, north = pole == "n" }
      local m = brass.density * o.spoke_length * o.spoke_width * o.commutator_depth
      inertia = inertia + m * ((o.spoke_length ^ 2 + o.spoke_width ^ 2) / 12 + r * r)
    end
    -- The rotor is held to the play area's plane through its centre of mass
    -- (the rigid body's planar parts): a brass disk of the ring's mass as far
    -- on the other side keeps that centre in the spokes' plane.
    local ring = 8 * brass.density * o.spoke_length * o.spoke_width * o.commutator_depth
    local radius = o.hub_radius
    kit.cylinder { name = "counterweight", material = "brass", at = { C[1], C[2], -o.commutator_z },
                   radius = radius, depth = ring / (brass.density * math.pi * radius ^ 2) }
    kit.glue { name = "counterweight_glue", a = "axle", b = "counterweight" }
    inertia = inertia + ring * radius ^ 2 / 2
  end
  inertia = inertia + (extra_inertia or 0)
  kit.disk { name = "axle", material = "wood", at = C, radius = o.hub_radius,
             props = { angular_damping = o.bearing_drag / inertia } }
  kit.pin { name = "bearing", part = "axle", friction = o.axle_friction }
  return spokes, inertia, segments
end
