-- The kit's Lua API, checked from Lua: materials, the component list, new
-- components and materials, and the values parts return.
local kit = require "kit"

assert(kit.material("steel").density == 7850, "steel density")
assert(kit.material("rubber").restitution > kit.material("copper").restitution, "rubber bounces more than copper")
local names = table.concat(kit.materials(), ",")
assert(names == "brass,bronze,copper,felt,iron,rubber,steel,wood", names)
local parts = table.concat(kit.parts(), ",")
assert(parts == "armature,bar,battery,bell,capacitor,coil,contact,cylinder,disk,floor,glue,hinge,junction,lamp,magnet,photocell,pin,resistor,rope,spring,switch,wall,wire", parts)

-- The kit is read-only for everyone who requires it.
assert(not pcall(function() kit.bar = nil end), "kit must be read-only")

-- A part returns its name, for use in joints.
local arm = kit.bar { name = "arm", at = { 0, 1 }, length = 0.5 }
assert(arm == "arm")

-- Mods and scenes grow the kit.
kit.add_material("lead", { density = 11340, friction = 0.5, restitution = 0.1 })
kit.define("weight", {
  doc = "a lead ball",
  args = { { "at", "vec", required = true }, { "radius", "positive", default = 0.05 } },
  build = function(a)
    return { shape = "sphere", radius = a.radius, position = a.at, mass = 11340 * 4 / 3 * math.pi * a.radius ^ 3 }
  end,
})
kit.weight { name = "bob", at = { 0, 0.5 } }
kit.disk { name = "lead_disk", material = "lead", at = { 1, 1 }, radius = 0.1 }
