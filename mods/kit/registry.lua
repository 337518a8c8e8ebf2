-- The component registry: a component (a part template) is data plus a
-- function from arguments to properties.
--
--   registry.define("bar", {
--     doc  = "one line for docs and messages",
--     args = { { "length", "positive", required = true, doc = "m" }, ... },
--     build = function(args, ctx) return { shape = "box", ... } end,
--   })
--
-- Calling a component checks its arguments against `args` (unknown names with
-- a "did you mean", missing required ones, wrong types), fills defaults,
-- converts them (vectors to {x, y, z}, material names to material records),
-- calls `build`, applies the caller's raw `props` overrides and records the
-- object with the host's object{}. The host attributes the object, and any
-- error raised here, to the scene line that called the component.
--
-- Every component and material belongs to the mod that defined it (its
-- owner: "kit" for the kit's own, "" for a loose scene). A mod may add new
-- ones and replace its own, never another's: kit.define and kit.add_material
-- reach here through the kit each mod gets (init.lua), which passes the
-- requiring mod's name as the host gave it. This module is the kit's alone
-- (alloy.per_mod at the end), and what it hands out is read-only.
local geometry = require "kit.geometry"

local registry = {}

local components = {}  -- name -> { owner, doc, args, build, make } (frozen)
local materials = {}   -- name -> { name, owner, density, friction, restitution, ... } (frozen)
local placed = {}      -- object name -> position {x, y, z}, for parts made here

local function who(owner)
  return owner == "" and "the scene" or ("mod '" .. owner .. "'")
end

-- Refuses to let `owner` replace what another owns; the message names both.
local function check_owner(what, name, old, owner)
  if old and old.owner ~= owner then
    error(what .. " '" .. name .. "' belongs to " .. who(old.owner) .. "; " .. who(owner) ..
          " cannot redefine it (give yours another name, such as '" ..
          (owner == "" and "my" or owner) .. "_" .. name .. "')", 3)
  end
end

-- Errors are tables so that the host can name the object separately.
local function fail(object, message)
  error({ message = message, object = object }, 0)
end
registry.fail = fail

local function sorted_keys(t)
  local keys = {}
  for k in pairs(t) do keys[#keys + 1] = k end
  table.sort(keys)
  return keys
end

local function hint(name, candidates)
  local near = alloy.closest(name, candidates)
  return near and (" (did you mean '" .. near .. "'?)") or ""
end

local function is_number(v) return type(v) == "number" and v == v end

-- Argument types: a check that returns the converted value, or nil and what
-- was expected.
local types = {}
types.string = function(v)
  if type(v) == "string" then return v end
  return nil, "a string"
end
types.object = function(v)
  if type(v) == "string" and v ~= "" then return v end
  return nil, "the name of an object"
end
types.number = function(v)
  if is_number(v) and v > -math.huge and v < math.huge then return v end
  return nil, "a finite number"
end
types.positive = function(v)
  if is_number(v) and v > 0 and v < math.huge then return v end
  return nil, "a positive number"
end
types.nonnegative = function(v)
  if is_number(v) and v >= 0 and v < math.huge then return v end
  return nil, "a number >= 0"
end
types.boolean = function(v)
  if type(v) == "boolean" then return v end
  return nil, "true or false"
end
types.vec = function(v)
  if type(v) == "table" and (#v == 2 or #v == 3) then
    local ok = true
    for i = 1, #v do ok = ok and types.number(v[i]) ~= nil end
    if ok then return geometry.vec3(v) end
  end
  return nil, "a vector {x, y} or {x, y, z}"
end
types.extent = function(v)  -- a size: {x, y} or {x, y, z}, each positive
  local vec = types.vec(v)
  if vec and vec[1] > 0 and vec[2] > 0 and (#v == 2 or vec[3] > 0) then
    return { vec[1], vec[2], #v == 3 and vec[3] or nil }
  end
  return nil, "a size {width, height} or {x, y, z} of positive numbers"
end
types.range = function(v)
  if type(v) == "table" and #v == 2 and types.number(v[1]) and types.number(v[2]) and v[1] <= v[2] then
    return { v[1], v[2] }
  end
  return nil, "a range {low, high} with low <= high"
end
types.props = function(v)
  if type(v) == "table" then return v end
  return nil, "a table of raw properties"
end
types.material = function(v)
  if type(v) == "table" then
    for _, key in ipairs({ "density", "friction", "restitution" }) do
      if not is_number(v[key]) then return nil, "a material name or a table with density, friction and restitution" end
    end
    return v
  end
  if type(v) ~= "string" then return nil, "a material name" end
  local m = materials[v]
  if m then return m end
  return nil, "one of the kit's materials", "unknown material '" .. v .. "'" .. hint(v, sorted_keys(materials))
end

--- Adds a material for `owner`, or replaces one of its own.
function registry.add_material(owner, name, m)
  if type(name) ~= "string" or name == "" then error("a material needs a name", 3) end
  local checked, expected = types.material(m)
  if not checked then error("material '" .. tostring(name) .. "' must be " .. expected, 3) end
  check_owner("material", name, materials[name], owner)
  local copy = {}
  for k, v in pairs(m) do copy[k] = v end
  copy.name, copy.owner = name, owner
  materials[name] = alloy.freeze(copy)
end

function registry.material(name)
  return materials[name]
end

function registry.material_names()
  return sorted_keys(materials)
end

--- Where a part made by the kit was placed (nil for other objects): a copy.
function registry.placed(name)
  local p = placed[name]
  return p and { p[1], p[2], p[3] }
end

-- What a component's build gets as its second argument: the parts of the
-- registry a build needs, read-only.
local context = alloy.freeze({ placed = registry.placed, fail = fail, material = registry.material })

local function check_args(part, spec, args)
  local by_name = {}
  local names = {}
  for _, a in ipairs(spec.args) do
    by_name[a[1]] = a
    names[#names + 1] = a[1]
  end
  local object = type(args.name) == "string" and args.name or nil
  for _, key in ipairs(sorted_keys(args)) do
    if type(key) ~= "string" then
      fail(object, "kit." .. part .. " takes named arguments (name = value), not a list")
    end
    if not by_name[key] then
      fail(object, "kit." .. part .. " has no argument '" .. key .. "'" .. hint(key, names))
    end
  end
  local out = {}
  for _, a in ipairs(spec.args) do
    local key, kind = a[1], a[2]
    local v = args[key]
    if v == nil then v = a.default end
    if v == nil then
      if a.required then fail(object, "kit." .. part .. " needs '" .. key .. "'" .. (a.doc and (" (" .. a.doc .. ")") or "")) end
    else
      local converted, expected, message = types[kind](v)
      if converted == nil then
        fail(object, message or ("kit." .. part .. " '" .. key .. "' must be " .. expected .. ", got " .. tostring(v)))
      end
      out[key] = converted
    end
  end
  return out
end

local function make(part, spec)
  return function(args)
    if type(args) ~= "table" then
      fail(nil, "kit." .. part .. " takes a table of arguments: kit." .. part .. " { name = ..., ... }")
    end
    local a = check_args(part, spec, args)
    -- A failure inside build (a bug in a component, or one of its own checks)
    -- is reported for this object.
    local ok, props = pcall(spec.build, a, context)
    if not ok then
      if type(props) == "table" then
        props.object = props.object or a.name
        error(props, 0)
      end
      fail(a.name, tostring(props))
    end
    if type(props) ~= "table" then fail(a.name, "kit." .. part .. ": its build must return a table of properties") end
    props.name = a.name
    for k, v in pairs(a.props or {}) do props[k] = v end
    local at = props.position
    if a.name and type(at) == "table" then placed[a.name] = { at[1], at[2], at[3] } end
    object(props)
    return a.name
  end
end

--- Registers a component for `owner` (or replaces one of its own); returns
--- the function that makes one.
function registry.define(owner, part, spec)
  if type(part) ~= "string" or not part:match("^[%a_][%w_]*$") then
    error("a component needs a name made of letters, digits and _", 3)
  end
  if type(spec) ~= "table" or type(spec.build) ~= "function" or type(spec.args) ~= "table" then
    error("component '" .. part .. "' needs args (a list) and build (a function)", 3)
  end
  check_owner("part", "kit." .. part, components[part], owner)
  -- Every part may be named, and may override any raw property with props = {...}.
  -- The arguments are copied: the caller keeps no hold on the registered part.
  local args = { { "name", "string" } }
  for _, a in ipairs(spec.args) do
    if type(a) ~= "table" or type(a[1]) ~= "string" or not types[a[2]] then
      error("component '" .. part .. "': argument " .. tostring(type(a) == "table" and a[1] or a) ..
            " has unknown type " .. tostring(type(a) == "table" and a[2] or nil), 3)
    end
    local copy = {}
    for k, v in pairs(a) do copy[k] = v end
    args[#args + 1] = copy
  end
  args[#args + 1] = { "props", "props", doc = "raw property overrides" }
  local entry = { owner = owner, doc = spec.doc or "", args = args, build = spec.build }
  entry.make = make(part, entry)
  components[part] = alloy.freeze(entry)
  return entry.make
end

local function copy_deep(v)
  if type(v) ~= "table" then return v end
  local out = {}
  for k, x in pairs(v) do out[k] = copy_deep(x) end
  return out
end

--- A component's description (owner, doc, args, make), for docs and tools:
--- a copy, so that nobody changes the registered part through it.
function registry.component(part)
  local c = components[part]
  if not c then return nil end
  return { owner = c.owner, doc = c.doc, args = copy_deep(c.args), make = c.make }
end

--- The function that makes a component, or nil.
function registry.maker(part)
  local c = components[part]
  return c and c.make
end

function registry.names()
  return sorted_keys(components)
end

--- For a missing component: a function that reports it, naming the object.
function registry.unknown(part)
  return function(args)
    local object = type(args) == "table" and type(args.name) == "string" and args.name or nil
    local near = alloy.closest(tostring(part), registry.names())
    fail(object, "unknown part 'kit." .. tostring(part) .. "'" .. (near and (" (did you mean 'kit." .. near .. "'?)") or ""))
  end
end

-- The kit's own: other mods use it through `require "kit"`.
return alloy.per_mod(function(mod)
  if mod == "kit" then return registry end
end)
