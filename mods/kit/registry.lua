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
local geometry = require "kit.geometry"

local registry = {}

local components = {}  -- name -> spec
local materials = {}   -- name -> { density, friction, restitution, ... }
local placed = {}      -- object name -> position {x, y, z}, for parts made here

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

--- Adds or replaces a material.
function registry.add_material(name, m)
  local checked, expected = types.material(m)
  if not checked then error("material '" .. tostring(name) .. "' must be " .. expected, 2) end
  local copy = { name = name }
  for k, v in pairs(m) do copy[k] = v end
  materials[name] = copy
end

function registry.material(name)
  return materials[name]
end

function registry.material_names()
  return sorted_keys(materials)
end

--- Where a part made by the kit was placed (nil for other objects).
function registry.placed(name)
  return placed[name]
end

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
    local ok, props = pcall(spec.build, a, registry)
    if not ok then
      if type(props) == "table" then
        props.object = props.object or a.name
        error(props, 0)
      end
      fail(a.name, tostring(props))
    end
    props.name = a.name
    for k, v in pairs(a.props or {}) do props[k] = v end
    if a.name and props.position then placed[a.name] = props.position end
    object(props)
    return a.name
  end
end

--- Registers a component; returns the function that makes one.
function registry.define(part, spec)
  if type(part) ~= "string" or not part:match("^[%a_][%w_]*$") then
    error("a component needs a name made of letters, digits and _", 2)
  end
  if type(spec) ~= "table" or type(spec.build) ~= "function" or type(spec.args) ~= "table" then
    error("component '" .. part .. "' needs args (a list) and build (a function)", 2)
  end
  for _, a in ipairs(spec.args) do
    if type(a[1]) ~= "string" or not types[a[2]] then
      error("component '" .. part .. "': argument " .. tostring(a[1]) .. " has unknown type " .. tostring(a[2]), 2)
    end
  end
  -- Every part may be named, and may override any raw property with props = {...}.
  local args = { { "name", "string" } }
  for _, a in ipairs(spec.args) do args[#args + 1] = a end
  args[#args + 1] = { "props", "props", doc = "raw property overrides" }
  local entry = { doc = spec.doc or "", args = args, build = spec.build }
  entry.make = make(part, entry)
  components[part] = entry
  return entry.make
end

function registry.component(part)
  return components[part]
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

return registry
