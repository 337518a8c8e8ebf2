-- Bodies of the kit: bars and disks that move in the play area, and static
-- floors and walls. Each is a function from arguments to properties; mass
-- comes from the material's density and the part's volume. A part of a
-- conductive material conducts; one of a ferromagnetic material may be soft
-- iron (`magnetic`).
local geometry = require "kit.geometry"
local physics = require "kit.physics"

local bodies = {}

-- Arguments every moving part takes.
local function motion_args(list)
  list[#list + 1] = { "angle", "number", default = 0, doc = "rotation about +z, rad" }
  list[#list + 1] = { "velocity", "vec", doc = "initial velocity, m/s" }
  list[#list + 1] = { "spin", "number", doc = "initial angular velocity about +z, rad/s" }
  list[#list + 1] = { "pinned", "boolean", default = false, doc = "held in place on the play area" }
  list[#list + 1] = { "magnetic", "boolean",
                      doc = "soft iron, magnetised by nearby magnets and coils; default: the material's soft_magnetic (iron)" }
  return list
end

--- The electrical and magnetic properties a material gives a part.
--- `length` is the part's extent along its x axis, `volume` its volume.
local function material_props(a, p, length, volume)
  local m = a.material
  if m.conductive then p.conductive = true end
  local magnetic = a.magnetic
  if magnetic == nil then magnetic = m.soft_magnetic == true end
  if magnetic then
    if not m.susceptibility then
      error("material '" .. (m.name or "this material") .. "' is not ferromagnetic (it has no susceptibility): it cannot be magnetic", 0)
    end
    p.magnet = "soft_iron"
    p.susceptibility = m.susceptibility
    if m.saturation_magnetization then
      -- The pole strength at saturation: Ms V spread over the pole separation.
      p.saturation_pole = m.saturation_magnetization * volume / (physics.magnetic_length_ratio * length)
    end
  end
  return p
end

local function moving_body(a, shape_props, volume)
  local m = a.material
  local p = shape_props
  p.position = a.at
  p.orientation = geometry.quat_z(a.angle)
  p.density = m.density
  p.mass = m.density * volume
  p.friction = m.friction
  p.restitution = m.restitution
  p.planar = true
  if a.pinned then p.pinned = true end
  if a.velocity then p.velocity = a.velocity end
  if a.spin then p.angular_velocity = { 0, 0, a.spin } end
  return p
end

bodies.bar = {
  doc = "a straight bar of rectangular section lying in the play area",
  args = motion_args({
    { "material", "material", default = "steel" },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "length", "positive", required = true, doc = "along the bar, m" },
    { "width", "positive", default = 0.02, doc = "across the bar in the plane, m" },
    { "depth", "positive", doc = "thickness out of the plane, m; default: the width" },
  }),
  build = function(a)
    local size = { a.length, a.width, a.depth or a.width }
    local volume = geometry.box_volume(size)
    return material_props(a, moving_body(a, { shape = "box", size = size }, volume), a.length, volume)
  end,
}

bodies.armature = {
  doc = "a soft-iron bar (an armature, a striker): magnets and coils pull on it",
  args = motion_args({
    { "material", "material", default = "iron" },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "length", "positive", required = true, doc = "along the bar, m: the field along this axis magnetises it" },
    { "width", "positive", default = 0.01, doc = "across the bar in the plane, m" },
    { "depth", "positive", doc = "thickness out of the plane, m; default: the width" },
  }),
  build = function(a)
    if a.magnetic == false then error("an armature is magnetic: leave out 'magnetic' or use kit.bar", 0) end
    a.magnetic = true
    return bodies.bar.build(a)
  end,
}

-- A ball: the sphere of the kit's first scenes, kept so that they (and their
-- measured figures) stay as they were. It rolls at 5/7 g sin(theta) down a
-- slope; a wheel or a coin, which rolls at 2/3, is kit.cylinder.
bodies.disk = {
  doc = "a ball rolling in the play area (a sphere; a wheel or a coin is kit.cylinder)",
  args = motion_args({
    { "material", "material", default = "steel" },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "radius", "positive", required = true, doc = "m" },
  }),
  build = function(a)
    local volume = geometry.sphere_volume(a.radius)
    return material_props(a, moving_body(a, { shape = "sphere", radius = a.radius }, volume), 2 * a.radius, volume)
  end,
}

bodies.cylinder = {
  doc = "a wheel, a coin, a pulley: a solid cylinder whose axis is out of the play area, so that it is a true disk in it",
  args = motion_args({
    { "material", "material", default = "steel" },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "radius", "positive", required = true, doc = "m" },
    { "depth", "positive", default = 0.02, doc = "thickness out of the plane (along the axis), m" },
  }),
  build = function(a)
    -- The magnetism resolver's bulk model knows bars, spheres and capsules,
    -- not cylinders: an iron cylinder is plain iron, and asking for a
    -- magnetic one is refused rather than ignored.
    if a.magnetic then
      error("a cylinder cannot be magnetic (the magnetism resolver models bars, spheres and capsules): use kit.disk or kit.armature", 0)
    end
    a.magnetic = false
    local volume = geometry.cylinder_volume(a.radius, a.depth)
    return material_props(a, moving_body(a, { shape = "cylinder", radius = a.radius, length = a.depth }, volume),
                          2 * a.radius, volume)
  end,
}

local function static_args(default_material)
  return {
    { "material", "material", default = default_material },
    { "at", "vec", required = true, doc = "centre {x, y}, m" },
    { "size", "extent", required = true, doc = "{width, height} in the plane, m" },
    { "depth", "positive", default = 1, doc = "extent out of the plane, m: wide enough for any part" },
    { "angle", "number", default = 0, doc = "rotation about +z, rad (a tilted floor is a ramp)" },
  }
end

local function static_body(a)
  local m = a.material
  return {
    shape = "box",
    size = { a.size[1], a.size[2], a.size[3] or a.depth },
    position = a.at,
    orientation = geometry.quat_z(a.angle),
    static = true,
    friction = m.friction,
    restitution = m.restitution,
    conductive = m.conductive or nil,
  }
end

bodies.floor = {
  doc = "a static slab: the ground, a shelf, or tilted, a ramp",
  args = static_args("wood"),
  build = static_body,
}

bodies.wall = {
  doc = "a static upright slab that bounds the play area",
  args = static_args("wood"),
  build = static_body,
}

-- The kit's own: other mods use these parts through `require "kit"`.
return alloy.per_mod(function(mod)
  if mod == "kit" then return bodies end
end)
