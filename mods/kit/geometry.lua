-- Play-area geometry: points are {x, y} (z = 0) or {x, y, z}; a part's
-- rotation in the plane is an angle about +z in radians.
local geometry = {}

--- {x, y} or {x, y, z} -> {x, y, z}
function geometry.vec3(v)
  return { v[1], v[2], v[3] or 0 }
end

--- The quaternion {w, x, y, z} of a rotation by `angle` radians about +z.
function geometry.quat_z(angle)
  return { math.cos(angle / 2), 0, 0, math.sin(angle / 2) }
end

--- Volume of a box of full extents {x, y, z}.
function geometry.box_volume(size)
  return size[1] * size[2] * size[3]
end

function geometry.sphere_volume(radius)
  return 4 / 3 * math.pi * radius ^ 3
end

--- Volume of a solid cylinder of `radius` and `length` along its axis.
function geometry.cylinder_volume(radius, length)
  return math.pi * radius ^ 2 * length
end

return geometry
