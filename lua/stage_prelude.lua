-- The host side of Lua stages, run once in each mod's Lua state. It is the
-- only Lua code that holds the FFI: it turns the C structs of stage_abi.hpp
-- into the objects a mod's stage works with (w, columns, interaction
-- functions), checks every index and value on the way, and gives the mod's
-- environment its deterministic pairs and random generator, its vec3 and
-- quat, and the budget tick. Nothing here is reachable from a mod: mods get
-- closures over these locals, never the locals themselves.
--
-- Called with: ffi, the api (lightuserdata), the budget (userdata), the
-- over-budget check (C function), a table of host C functions, the cdef,
-- the mod's name.
local ffi, api_ud, budget_ud, over_budget, host, cdef, mod_name = ...

ffi.cdef(cdef)
local api = ffi.cast("alloy_api*", api_ud)
local budget = ffi.cast("alloy_budget*", budget_ud)
local column_ptr = ffi.typeof("alloy_column*")
local call_ptr = ffi.typeof("alloy_call*")
local contact_ptr = ffi.typeof("const alloy_contact*")
local cmd_ptr = ffi.typeof("const double*")
local bulk_ptr = ffi.typeof("alloy_bulk*")
local load_ptr = ffi.typeof("alloy_load*")
local u32_ptr = ffi.typeof("uint32_t*")
local cast = ffi.cast

local error, type, tostring, select, setmetatable, pairs_raw, next = error, type, tostring, select, setmetatable, pairs, next
local rawget = rawget
local newproxy, getmetatable = newproxy, getmetatable
local floor, sqrt, huge = math.floor, math.sqrt, math.huge
local sort, concat = table.sort, table.concat
local format = string.format

local M = {}

-- The tick: one counter decrement per loop iteration and function call of the
-- mod's code (budget_ticks.hpp). The host refills it, or raises, when it runs out.
function M.tick()
  local t = budget.ticks - 1
  budget.ticks = t
  if t < 0 then over_budget() end
end

---------------------------------------------------------------------------
-- vec3 and quat: immutable values with arithmetic.

local vec3_t = ffi.typeof("const alloy_vec3")
local quat_t = ffi.typeof("const alloy_quat")
local vec3_ct, quat_ct = ffi.typeof("alloy_vec3"), ffi.typeof("alloy_quat")  -- istype ignores const
local istype = ffi.istype
local is_vec3 = function(v) return istype(vec3_ct, v) end
local is_quat = function(v) return istype(quat_ct, v) end

local function vec3(x, y, z) local r = vec3_t(x or 0, y or 0, z or 0) return r end

-- The host's functions below follow one rule (docs/architecture.md, "The
-- Lua boundary"): no code of the mod runs while they hold memory the host
-- lent for a call. They turn every argument into plain numbers first, with
-- no metamethod (which could yield, re-enter the host or fail), then check
-- that the call they belong to is still on, and only then take a pointer
-- into the host's buffers and write, with nothing in between.

-- A vec3 argument as three plain numbers: a vec3 (x, y, z are struct
-- fields: no code runs), or a table read raw, {x = , y = , z = } or
-- {x, y, z} (z may be left out). A table's metatable is not consulted.
-- Returns nil if v is none of these.
local function xyz(v)
  if is_vec3(v) then return v.x, v.y, v.z end
  if type(v) == "table" then
    local x, y, z = rawget(v, "x"), rawget(v, "y"), rawget(v, "z")
    if x == nil then x = rawget(v, 1) end
    if y == nil then y = rawget(v, 2) end
    if z == nil then
      z = rawget(v, 3)
      if z == nil then z = 0 end
    end
    if type(x) == "number" and type(y) == "number" and type(z) == "number" then return x, y, z end
  end
  return nil
end

-- Raises the error for a value that is not a vec3; `level` as the caller
-- would give it to error().
local function not_vec3(v, what, level)
  local got = type(v)
  if got == "table" then
    got = getmetatable(v) ~= nil and "a table with a metatable (read raw: host functions run no metamethod)"
      or "a table without three numbers"
  end
  error(what .. " must be a vec3 (vec3(x, y, z) or a table {x, y, z} of numbers), got " .. got, level + 1)
end

local function vtext(x, y, z) return format("{%g, %g, %g}", x, y, z) end

-- A value of the mod's in a message, without running its code (tostring
-- calls a table's __tostring).
local function shown(v)
  local t = type(v)
  if t == "string" or t == "number" or t == "boolean" or t == "nil" then return tostring(v) end
  return "a " .. t
end

local vec3_methods = {
  length = function(a) local l = sqrt(a.x * a.x + a.y * a.y + a.z * a.z) return l end,
  length2 = function(a) return a.x * a.x + a.y * a.y + a.z * a.z end,
  dot = function(a, b) return a.x * b.x + a.y * b.y + a.z * b.z end,
  cross = function(a, b) local r = vec3_t(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x) return r end,
  normalized = function(a)
    local l = sqrt(a.x * a.x + a.y * a.y + a.z * a.z)
    if l == 0 then return a end
    local r = vec3_t(a.x / l, a.y / l, a.z / l)
    return r
  end,
  unpack = function(a) return a.x, a.y, a.z end,
}
ffi.metatype("alloy_vec3", {
  __add = function(a, b) local r = vec3_t(a.x + b.x, a.y + b.y, a.z + b.z) return r end,
  __sub = function(a, b) local r = vec3_t(a.x - b.x, a.y - b.y, a.z - b.z) return r end,
  __unm = function(a) local r = vec3_t(-a.x, -a.y, -a.z) return r end,
  __mul = function(a, b)
    if type(a) == "number" then local r = vec3_t(a * b.x, a * b.y, a * b.z) return r end
    if type(b) == "number" then local r = vec3_t(a.x * b, a.y * b, a.z * b) return r end
    error("vec3 * vec3 is not defined: use a:dot(b) or a:cross(b)", 2)
  end,
  __div = function(a, s) local r = vec3_t(a.x / s, a.y / s, a.z / s) return r end,
  __eq = function(a, b) return is_vec3(a) and is_vec3(b) and a.x == b.x and a.y == b.y and a.z == b.z end,
  __tostring = function(a) return format("{%g, %g, %g}", a.x, a.y, a.z) end,
  __index = vec3_methods,
})

local quat_methods = {
  -- Rotates a vec3 by this unit quaternion.
  rotate = function(q, v)
    local ux, uy, uz = q.x, q.y, q.z
    local tx, ty, tz = 2 * (uy * v.z - uz * v.y), 2 * (uz * v.x - ux * v.z), 2 * (ux * v.y - uy * v.x)
    local r = vec3_t(v.x + q.w * tx + (uy * tz - uz * ty), v.y + q.w * ty + (uz * tx - ux * tz),
                     v.z + q.w * tz + (ux * ty - uy * tx))
    return r
  end,
  -- The angle about +z of a rotation in the play area, rad.
  angle_z = function(q) return 2 * math.atan2(q.z, q.w) end,
}
ffi.metatype("alloy_quat", {
  __mul = function(a, b)
    local r = quat_t(a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                     a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w)
    return r
  end,
  __eq = function(a, b)
    return is_quat(a) and is_quat(b) and a.w == b.w and a.x == b.x and
      a.y == b.y and a.z == b.z
  end,
  __tostring = function(q) return format("{%g, %g, %g, %g}", q.w, q.x, q.y, q.z) end,
  __index = quat_methods,
})
local function quat(w, x, y, z) local r = quat_t(w or 1, x or 0, y or 0, z or 0) return r end
local function quat_z(angle) local r = quat_t(math.cos(angle / 2), 0, 0, math.sin(angle / 2)) return r end

M.vec3 = setmetatable({ new = vec3, zero = vec3_t(0, 0, 0) }, {
  __call = function(_, x, y, z) local r = vec3_t(x or 0, y or 0, z or 0) return r end,
  __metatable = "vec3",
  __newindex = function() error("vec3 is read-only", 2) end,
})
M.quat = setmetatable({ new = quat, identity = quat_t(1, 0, 0, 0), from_angle_z = quat_z }, {
  __call = function(_, w, x, y, z) local r = quat(w, x, y, z) return r end,
  __metatable = "quat",
  __newindex = function() error("quat is read-only", 2) end,
})

---------------------------------------------------------------------------
-- Determinism: pairs in sorted key order, and a seeded generator per mod.

local key_rank = { number = 1, string = 2, boolean = 3 }
local function key_less(a, b)
  local ta, tb = type(a), type(b)
  if ta ~= tb then return key_rank[ta] < key_rank[tb] end
  if ta == "boolean" then return (not a) and b end
  return a < b
end

-- pairs(t): every key of t in a fixed order (numbers ascending, then strings,
-- then false, true), the same on every run. Keys of other types (tables,
-- functions) have no such order: iterate a list of them instead.
function M.pairs(t)
  if type(t) ~= "table" then error("bad argument #1 to 'pairs' (table expected, got " .. type(t) .. ")", 2) end
  local keys, n = {}, 0
  for k in next, t do
    if not key_rank[type(k)] then
      error("pairs: a key of type " .. type(k) .. " has no deterministic order; keep such keys in a list", 2)
    end
    n = n + 1
    keys[n] = k
  end
  sort(keys, key_less)
  local i = 0
  return function()
    i = i + 1
    local k = keys[i]
    if k == nil then return nil end
    return k, t[k]
  end, t, nil
end

-- xorshift64* seeded from the mod's name (FNV-1a): the same numbers on every run.
local rng = ffi.new("uint64_t[1]")
local function seed(s)
  local h = 14695981039346656037ULL
  s = tostring(s)
  for i = 1, #s do h = bit.bxor(h, s:byte(i)) * 1099511628211ULL end
  if h == 0ULL then h = 88172645463325252ULL end
  rng[0] = h
end
seed(mod_name)
local function next_u53()
  local x = rng[0]
  x = bit.bxor(x, bit.rshift(x, 12))
  x = bit.bxor(x, bit.lshift(x, 25))
  x = bit.bxor(x, bit.rshift(x, 27))
  rng[0] = x
  return tonumber(bit.rshift(x * 2685821657736338717ULL, 11))
end
-- math.random as in Lua: () in [0, 1), (m) in [1, m], (m, n) in [m, n].
function M.random(m, n)
  local r = next_u53() / 9007199254740992
  if m == nil then return r end
  if n == nil then m, n = 1, m end
  if type(m) ~= "number" or type(n) ~= "number" or m > n then error("bad argument to 'random' (interval is empty)", 2) end
  m, n = floor(m), floor(n)
  return m + floor(r * (n - m + 1))
end
function M.randomseed(s) seed(s) end

---------------------------------------------------------------------------
-- String patterns: the state's find, match, gmatch and gsub are the host's
-- bounded matcher already (lua/lua_patterns.hpp), which counts its steps
-- against the mod's ticks; nothing to add here.
M.string = {}

---------------------------------------------------------------------------
-- Stages. A stage record per C++ stage instance: its w (what the mod's
-- functions get), the proxies of its columns, and its current definition.

-- `level`: as the caller would give it to error() (2: the caller's caller).
local function not_in_call(what, level)
  error(what .. " can only be used while the stage that got it runs", (level or 2) + 1)
end

local function fail(rec, level)
  error(host.last_error(rec.handle), level + 1)
end

local readers = {}  -- kind -> function(info, i) -> value
readers[0] = function(info, i) return info.num[i] end
readers[1] = function(info, i) return tonumber(info.integer[i]) end
readers[2] = function(info, i) return info.boolean[i] ~= 0 end
readers[3] = function(info, i) local p = info.vec3[i] local r = vec3_t(p.x, p.y, p.z) return r end
readers[4] = function(info, i) local p = info.quat[i] local r = quat_t(p.w, p.x, p.y, p.z) return r end
readers[6] = function(info, i)
  local r = info.ref[i]
  if r.index == 0xffffffff then return nil end
  return r.index
end

local function check_finite(v, name)
  if type(v) ~= "number" then error("'" .. name .. "' takes numbers, got " .. type(v), 3) end
  if v ~= v or v == huge or v == -huge then error("'" .. name .. "' must be finite, got " .. tostring(v), 3) end
end

-- The read-only proxy of column k; with `writable`, also its writer.
local function column_proxy(rec, k, c)
  local info, handle, ptr, name, kind = rec.anchored(rec.infos + k), rec.handle, rec.ptr, c.name, c.kind
  local read = readers[kind]
  if kind == 5 then
    local names = c.values
    read = function(info, i) local v = names[info.enumv[i] + 1] return v end
  elseif kind == 7 then
    read = function(_, i) local v = host.slow_get(handle, k, i) return v end
  end
  -- for i in col:each(): the slots of the members; the position is kept in
  -- a small table (a closure per loop would keep the caller out of the JIT).
  -- A loop that ran to its end gives its table back for the next loop, so
  -- that a stage's call allocates nothing (each allocation brings the
  -- garbage collector's next step closer, paid for in some later call).
  -- A table is given back once; a loop left early leaves its own to the GC.
  local free, nfree = {}, 0
  local function step(st)
    local j = st[1] + 1
    st[1] = j
    if j < info.count then
      local m = info.members[j]
      return m
    end
    if st[2] then
      st[2] = false
      nfree = nfree + 1
      free[nfree] = st
    end
  end
  -- Most columns hold every object of the world, in a world whose slots
  -- are dense: the members are then 0 .. count-1 (they are ascending and
  -- distinct, so the last one is count-1 only if each is its own position).
  -- Such a loop needs no state but the slot itself, the control value of
  -- the for: no table to store the position into, no members to load.
  -- The count is read at each step, as above, so that a loop kept past
  -- its call ends there; a slot it gives is checked wherever it is used.
  local function dense_step(_, i)
    if type(i) ~= "number" then return nil end  -- a mod calling it by hand
    local j = i + 1
    if j < info.count then return j end
  end
  local function each()
    local count = info.count
    if count == 0 or info.members[count - 1] == count - 1 then return dense_step, nil, -1 end
    local st
    if nfree > 0 then
      st = free[nfree]
      free[nfree] = nil
      nfree = nfree - 1
      st[1], st[2] = -1, true
    else
      st = { -1, true }
    end
    return step, st, nil
  end
  local methods = {
    each = each,
    count = function() return info.count end,
    has = function(_, i)
      if info.n == 0 then not_in_call("column '" .. name .. "'") end
      local r = api.has(ptr, k, i)
      if r < 0 then fail(rec, 2) end
      return r == 1
    end,
    name = name,
  }
  local write
  -- Each writer converts the value first, then checks the call and the
  -- slot, then writes: nothing of the mod's runs after the check.
  local what = "'" .. name .. "'"
  local function slot_in_call(i)  -- for the writers of properties, whose slot C++ checks again
    if info.n == 0 then not_in_call("column '" .. name .. "'", 3) end
    if type(i) ~= "number" then error("column '" .. name .. "': no object in slot " .. shown(i), 3) end
  end
  if c.output then
    -- A derived set's own output: written straight into the set's arrays.
    local function output_slot(i)
      if info.n == 0 then not_in_call("column '" .. name .. "'", 3) end
      if not (type(i) == "number" and i >= 0 and i < info.n and i == floor(i)) then
        error("column '" .. name .. "': no object in slot " .. shown(i), 4)
      end
    end
    if kind == 3 then
      write = function(_, i, v)
        local x, y, z = xyz(v)
        if x == nil then not_vec3(v, what, 2) end
        check_finite(x, name) check_finite(y, name) check_finite(z, name)
        output_slot(i)
        local o = info.out_vec3 + i
        o.x, o.y, o.z = x, y, z
        info.out_present[i] = 1
      end
    else
      write = function(_, i, v)
        check_finite(v, name)
        output_slot(i)
        info.out_num[i] = v
        info.out_present[i] = 1
      end
    end
  elseif c.writable then
    if kind == 3 then
      write = function(_, i, v)
        local x, y, z = xyz(v)
        if x == nil then not_vec3(v, what, 2) end
        slot_in_call(i)
        if api.set_vec3(ptr, k, i, x, y, z) ~= 0 then fail(rec, 2) end
      end
    elseif kind == 4 then
      write = function(_, i, q)
        if not is_quat(q) then error(what .. " takes a quat", 2) end
        local qw, qx, qy, qz = q.w, q.x, q.y, q.z
        slot_in_call(i)
        if api.set_quat(ptr, k, i, qw, qx, qy, qz) ~= 0 then fail(rec, 2) end
      end
    elseif kind == 2 then
      write = function(_, i, v)
        if type(v) ~= "boolean" then error(what .. " takes true or false", 2) end
        slot_in_call(i)
        if api.set_scalar(ptr, k, i, v and 1 or 0) ~= 0 then fail(rec, 2) end
      end
    elseif kind == 5 then
      local index = {}
      for j, n in ipairs(c.values) do index[n] = j - 1 end
      write = function(_, i, v)
        local e = type(v) == "string" and index[v] or nil
        if e == nil then error(what .. " has no value '" .. shown(v) .. "'", 2) end
        slot_in_call(i)
        if api.set_scalar(ptr, k, i, e) ~= 0 then fail(rec, 2) end
      end
    elseif kind == 0 or kind == 1 then
      write = function(_, i, v)
        if type(v) ~= "number" then error(what .. " takes a number, got " .. type(v), 2) end
        slot_in_call(i)
        if api.set_scalar(ptr, k, i, v) ~= 0 then fail(rec, 2) end
      end
    else
      write = function(_, i, v)
        slot_in_call(i)
        host.slow_set(handle, k, i, v)  -- C: converts v to a string, runs no metamethod
      end
    end
  end
  local function index(_, i)
    if type(i) == "number" then
      if i >= 0 and i < info.n then
        local v = read(info, i)
        return v
      end
      if info.n == 0 then not_in_call("column '" .. name .. "'") end
      error("column '" .. name .. "': no object in slot " .. tostring(i), 2)
    end
    return methods[i]
  end
  -- A proxy is a userdata, not a table: indexing a table with a number
  -- makes the compiled loop test the key against the table's array part
  -- first (a conversion, a compare and a spilled size per column read);
  -- a userdata goes straight to __index. It also has no raw fields a mod
  -- could set, and # gives the count (Lua 5.1 ignores __len on tables).
  local function proxy(mt)
    mt.__metatable = "column"
    local u = newproxy(true)
    local m = getmetatable(u)
    for key, v in next, mt do m[key] = v end
    return u
  end
  local reader = proxy({
    __index = index,
    __newindex = function() error("column '" .. name .. "' is read-only here (declare it in writes)", 2) end,
    __len = function() return info.count end,
    __tostring = function() return "column '" .. name .. "'" end,
  })
  if not write then return reader end
  local writer = proxy({
    __index = index,
    __newindex = write,
    __len = function() return info.count end,
    __tostring = function() return "column '" .. name .. "' (writable)" end,
  })
  return reader, writer
end

-- Converts one argument of an interaction function into plain numbers, in
-- the table t from position j (returns the next position), checked here
-- where the mod's line is known (the slot's object being alive is checked
-- by C++ when the commands are performed). No code of the mod runs.
local function finite(x) return x - x == 0 end  -- false for NaN and infinities
local converters = {
  number = function(t, j, v, what)
    if type(v) ~= "number" then error(what .. " takes a number, got " .. type(v), 3) end
    if not finite(v) then error(what .. ": arguments must be finite, got " .. tostring(v), 3) end
    t[j] = v
    return j + 1
  end,
  object = function(t, j, v, what)
    if type(v) ~= "number" then error(what .. " takes an object (a slot number), got " .. type(v), 3) end
    if not (v >= 0 and v < 4294967296 and v == floor(v)) then
      error(what .. ": no object in slot " .. tostring(v), 3)
    end
    t[j] = v
    return j + 1
  end,
  vec3 = function(t, j, v, what)
    local x, y, z = xyz(v)
    if x == nil then not_vec3(v, what, 3) end
    -- 0 if all three are finite, NaN otherwise: one test instead of three.
    if not ((x - x) + (y - y) + (z - z) == 0) then
      error(what .. ": arguments must be finite, got " .. vtext(x, y, z), 3)
    end
    t[j], t[j + 1], t[j + 2] = x, y, z
    return j + 3
  end,
  none = function(t, j) return j end,
}
local width = { number = 1, object = 1, vec3 = 3 }

-- The command buffer of an interaction's calls, and the functions that
-- queue interaction functions of its target into it. The write position and
-- the room left live in upvalues of these closures during a call, not in the
-- C struct: LuaJIT keeps them in registers across the iterations of a mod's
-- loop, where a field of the struct would be stored and reloaded (through
-- memory) after every double written into the buffer. begin() takes them
-- from the struct when a call starts, finish() hands the length back when the
-- mod's function returns (a call that fails performs nothing, so a length
-- left behind by an error is never read).
local function command_queue(rec)
  local call, ptr = rec.call, rec.ptr
  local len, cap = 0, 0
  local q = {}
  function q.begin()
    len, cap = call.buf_len, call.buf_cap
  end
  function q.finish()
    call.buf_len = len
  end
  -- The function that queues interaction function `index`: it appends
  -- {index, slot, arguments...} to the buffer. The slot must hold a live
  -- object (call.ids, the host's per-slot ids for this call), checked
  -- here where the mod's line is known, so that the host performs the
  -- records without looking each object up again.
  function q.target_function(index, fname, kinds, record)
    if record then return q.record_function(fname, kinds, record) end
    local n = #kinds
    if n > 4 then error("interaction function '" .. fname .. "' takes more than 4 arguments") end
    local stride = 2
    for j = 1, n do stride = stride + width[kinds[j]] end
    local c1, c2, c3, c4 = converters[kinds[1] or "none"], converters[kinds[2] or "none"],
                           converters[kinds[3] or "none"], converters[kinds[4] or "none"]
    local what = "'" .. fname .. "'"
    local args = {}  -- the arguments as numbers, from their conversion to their copy
    return function(i, a1, a2, a3, a4)
      local epoch = call.epoch
      -- 1. The arguments, as plain numbers.
      if type(i) ~= "number" then error(what .. " takes an object (a slot number) first, got " .. type(i), 2) end
      local m = c1(args, 1, a1, what)
      m = c2(args, m, a2, what)
      m = c3(args, m, a3, what)
      m = c4(args, m, a4, what)
      -- 2. The call this function was entered in is still on; the object lives.
      if call.in_call == 0 or call.epoch ~= epoch then not_in_call(what) end
      if not (i >= 0 and i < call.slots and i == floor(i)) then
        error(what .. ": no object in slot " .. tostring(i), 2)
      end
      if call.ids[i] == 0ULL then error(what .. ": the object in slot " .. tostring(i) .. " was destroyed", 2) end
      -- 3. Only now the buffer: room, and the record, with nothing in between.
      local o = len
      if o + stride > cap then
        if api.grow(ptr) ~= 0 then fail(rec, 2) end
        cap = call.buf_cap
      end
      local b = call.buf
      b[o] = index
      b[o + 1] = i
      for j = 1, m - 1 do b[o + 1 + j] = args[j] end
      len = o + stride
    end
  end
  -- The same for a target that takes load records in place (the rigid
  -- body, call.loads): each call writes one record of kind `record` into
  -- the target's own queue, {id, value, point}, with the object's id
  -- (slot and generation) copied from call.ids, so that the host keeps the
  -- records as they are when the call returns. The room is not cleared by
  -- the host (it reuses the queue's storage): every record gets its id,
  -- value and kind here, and its point when the kind has one.
  function q.record_function(fname, kinds, record)
    local what = "'" .. fname .. "'"
    local at = #kinds == 2
    if not ((#kinds == 1 or at) and kinds[1] == "vec3" and (not at or kinds[2] == "vec3")) then
      error("interaction function '" .. fname .. "' cannot be written in place")
    end
    return function(i, v, p)
      local epoch = call.epoch
      -- 1. The arguments, as plain numbers.
      if type(i) ~= "number" then error(what .. " takes an object (a slot number) first, got " .. type(i), 2) end
      local x, y, z = xyz(v)
      if x == nil then not_vec3(v, what, 2) end
      -- 0 if all three are finite, NaN otherwise: one test instead of three.
      if not ((x - x) + (y - y) + (z - z) == 0) then
        error(what .. ": arguments must be finite, got " .. vtext(x, y, z), 2)
      end
      local px, py, pz
      if at then
        px, py, pz = xyz(p)
        if px == nil then not_vec3(p, what, 2) end
        if not ((px - px) + (py - py) + (pz - pz) == 0) then
          error(what .. ": arguments must be finite, got " .. vtext(px, py, pz), 2)
        end
      end
      -- 2. The call this function was entered in is still on; the object lives.
      if call.in_call == 0 or call.epoch ~= epoch then not_in_call(what) end
      if not (i >= 0 and i < call.slots and i == floor(i)) then
        error(what .. ": no object in slot " .. tostring(i), 2)
      end
      local id = call.ids[i]
      if id == 0ULL then error(what .. ": the object in slot " .. tostring(i) .. " was destroyed", 2) end
      -- 3. Only now the queue: room, and the record, with nothing in between.
      local o = len
      if o >= cap then
        if api.grow(ptr) ~= 0 then fail(rec, 2) end
        cap = call.buf_cap
      end
      local r = load_ptr(call.loads) + o
      r.id, r.vx, r.vy, r.vz, r.kind = id, x, y, z, record
      if at then r.px, r.py, r.pz = px, py, pz end
      len = o + 1
    end
  end
  -- A bulk buffer's writer and reader for a target taking records in
  -- place: the first write to a member's slot appends a record of kind
  -- `record` (its index kept in the buffer's values, read as one uint32 per
  -- slot: half the memory traffic of a double per slot), a later
  -- write overwrites it, a read gives it back. `check` refuses slots that
  -- are not members and buffers of a call that is over; the writer makes
  -- the same checks itself (the hot path of the bulk form): with `check`,
  -- a closure of its own, the compiled loop would read present[i] twice,
  -- through two copies of the buffer's pointer (anchored pointers are not
  -- folded into constants, so LuaJIT cannot tell the two are the same).
  function q.bulk_records(bk, record, what, check, fn, col)
    local function set(_, i, v)
      local x, y, z = xyz(v)
      if x == nil then not_vec3(v, what, 2) end
      if not ((x - x) + (y - y) + (z - z) == 0) then
        error(what .. ": values must be finite, got " .. vtext(x, y, z), 2)
      end
      -- After the conversion: the buffer is of a call that is on, i a member
      -- (check's tests, in the same order, with one read of present[i]).
      if bk.n == 0 or bk.fn ~= fn or bk.column ~= col or type(i) ~= "number" then check(i) end
      if not (i >= 0 and i < bk.n and i == floor(i)) then check(i) end
      local state = bk.present[i]
      local o
      if state == 1 then
        o = cast(u32_ptr, bk.values)[i]
      elseif state == 2 then
        check(i)
      else
        local id = call.ids[i]
        if id == 0ULL then error(what .. ": the object in slot " .. tostring(i) .. " was destroyed", 2) end
        o = len
        if o >= cap then
          if api.grow(ptr) ~= 0 then fail(rec, 2) end
          cap = call.buf_cap
        end
        len = o + 1
        local r = load_ptr(call.loads) + o
        r.id, r.kind = id, record
        cast(u32_ptr, bk.values)[i] = o
        bk.present[i] = 1
      end
      local r = load_ptr(call.loads) + o
      r.vx, r.vy, r.vz = x, y, z
    end
    local function get(_, i)
      check(i)
      if bk.present[i] ~= 1 then return nil end
      local r = load_ptr(call.loads) + cast(u32_ptr, bk.values)[i]
      local v = vec3_t(r.vx, r.vy, r.vz)
      return v
    end
    return set, get
  end
  return q
end

-- The bulk form of interaction function `index` (one number or vec3
-- argument): fname_each(col) gives a buffer indexed by slot, whose entries
-- written during the call are queued, for the members of `col`, when the call
-- returns (one C++ loop, no command record per object). The same buffer comes
-- back for the same column within a call; a buffer is only valid in its call.
-- The proxies are made once per buffer index and column, not per call.
local function bulk_function(rec, index, fname, kind, column_of, record)
  local ptr, call = rec.ptr, rec.call
  local what = "'" .. fname .. "_each'"
  local proxies = {}  -- [buffer index][column] -> proxy
  local function proxy(b, col, cname)
    local bk = rec.anchored(rec.bulks + b)
    local function check(i)
      if bk.n == 0 or bk.fn ~= index or bk.column ~= col then
        error(what .. ": a buffer can only be used in the call that got it", 3)
      end
      if type(i) ~= "number" then error(what .. ": index with an object (a slot number), got " .. type(i), 3) end
      if not (i >= 0 and i < bk.n and i == floor(i)) or bk.present[i] == 2 then
        error(what .. ": the object in slot " .. tostring(i) .. " is not a member of column '" .. cname .. "'", 3)
      end
    end
    local newindex, get
    if record then
      newindex, get = rec.queue.bulk_records(bk, record, what, check, index, col)
    elseif kind == "vec3" then
      newindex = function(_, i, v)
        local x, y, z = xyz(v)
        if x == nil then not_vec3(v, what, 2) end
        if not ((x - x) + (y - y) + (z - z) == 0) then
          error(what .. ": values must be finite, got " .. vtext(x, y, z), 2)
        end
        check(i)
        local o = i * 3
        local vals = bk.values
        vals[o], vals[o + 1], vals[o + 2] = x, y, z
        bk.present[i] = 1
      end
      get = function(_, i)
        check(i)
        if bk.present[i] ~= 1 then return nil end
        local vals, o = bk.values, i * 3
        local r = vec3_t(vals[o], vals[o + 1], vals[o + 2])
        return r
      end
    else
      newindex = function(_, i, v)
        if type(v) ~= "number" then error(what .. " takes numbers, got " .. type(v), 2) end
        if not (v - v == 0) then error(what .. ": values must be finite, got " .. tostring(v), 2) end
        check(i)
        bk.values[i] = v
        bk.present[i] = 1
      end
      get = function(_, i)
        check(i)
        if bk.present[i] ~= 1 then return nil end
        return bk.values[i]
      end
    end
    local u = newproxy(true)  -- a userdata, as column proxies are (column_proxy)
    local m = getmetatable(u)
    m.__index = get
    m.__newindex = newindex
    m.__metatable = "bulk buffer"
    m.__tostring = function() return "buffer of " .. what .. " over column '" .. cname .. "'" end
    return u
  end
  return function(col)
    if call.in_call == 0 then not_in_call(what) end
    local e = column_of[col]
    if not e then error(what .. " takes a column the stage reads (w:read(name)), got " .. type(col), 2) end
    local k = e.k
    local b = api.bulk(ptr, index, k)
    if b < 0 then fail(rec, 1) end
    local by_col = proxies[b]
    if not by_col then by_col = {} proxies[b] = by_col end
    local p = by_col[k]
    if not p then p = proxy(b, k, e.c.name) by_col[k] = p end
    return p
  end
end

-- Iterator over a resolver's queued commands of one function: slot, args...
local function command_iterator(rec, fname, f)
  local call = rec.call
  if call.in_call == 0 then not_in_call("w:commands", 3) end
  if api.commands(rec.ptr, f.index) ~= 0 then fail(rec, 2) end
  local recs, count, stride, epoch = call.cmd, call.cmd_count, call.cmd_stride, call.epoch
  local offsets, kinds, n = {}, f.kinds, #f.kinds
  local o = 1
  for j = 1, n do
    offsets[j] = o
    o = o + (kinds[j] == "vec3" and 3 or 1)
  end
  local function arg(b, j)
    local off = offsets[j]
    if kinds[j] == "vec3" then local r = vec3_t(b[off], b[off + 1], b[off + 2]) return r end
    return b[off]
  end
  local j = -1
  return function()
    if call.in_call == 0 or call.epoch ~= epoch then error("commands can only be read in the call that got them", 2) end
    j = j + 1
    if j >= count then return nil end
    local b = recs + j * stride
    if n == 0 then return b[0] end
    if n == 1 then return b[0], arg(b, 1) end
    if n == 2 then return b[0], arg(b, 1), arg(b, 2) end
    if n == 3 then return b[0], arg(b, 1), arg(b, 2), arg(b, 3) end
    return b[0], arg(b, 1), arg(b, 2), arg(b, 3), arg(b, 4)
  end
end

local contact_kinds = { began = 0, ongoing = 1, ended = 2, touching = 3 }

local function frozen(t, what)
  return setmetatable({}, {
    __index = t,
    __newindex = function(_, k) error(what .. " is read-only (cannot set '" .. shown(k) .. "')", 2) end,
    __metatable = what,
    __len = function() return #t end,
  })
end

-- decl (from C++): name, kind, columns = { {name, kind, writable, output, values, set}, ... },
-- functions (a resolver's own, for w:commands), target = { name, functions },
-- contacts (bool), settings, area. state: the mod's state table.
function M.new_stage(handle, infos_ud, call_ud, bulks_ud, decl, state)
  -- The C++ side lends three blocks (userdata), writes into them during
  -- calls and clears them when the stage goes. A pointer cdata does not keep
  -- its userdata alive, and a mod may keep a lone function of its stage
  -- (w.find, col.each) long after this record is gone: every pointer into
  -- the blocks that a closure keeps carries a finalizer holding all three,
  -- so that they live as long as any such pointer does.
  local function hold() return infos_ud, call_ud, bulks_ud end
  local function anchored(p) return ffi.gc(p, hold) end
  local rec = {
    handle = handle,  -- a lightuserdata, for the host's C functions
    ptr = ffi.cast("void*", handle),  -- the same as a cdata, for FFI calls (the JIT compiles only these)
    infos = anchored(ffi.cast(column_ptr, infos_ud)),
    call = anchored(ffi.cast(call_ptr, call_ud)),
    bulks = anchored(ffi.cast(bulk_ptr, bulks_ud)),
    anchored = anchored,
    decl = decl,
    def = {},
  }
  local reads, writes, outputs, derived = {}, {}, {}, {}
  local column_of = {}  -- proxy or name -> entry, for the bulk forms
  for k, c in ipairs(decl.columns) do
    local reader, writer = column_proxy(rec, k - 1, c)
    local entry = { k = k - 1, reader = reader, writer = writer, c = c }
    if not c.output then
      column_of[reader] = entry
      if writer then column_of[writer] = entry end
      if not c.set then column_of[c.name] = entry end
    end
    if c.set then
      derived[c.set] = derived[c.set] or {}
      derived[c.set][c.name] = entry
    elseif c.output then
      outputs[c.name] = entry
    else
      reads[c.name] = entry
      if c.writable then writes[c.name] = entry end
    end
  end
  local call, handle_, ptr = rec.call, handle, rec.ptr
  local function fetch(e)
    if call.in_call == 0 then not_in_call("w", 3) end
    if rec.infos[e.k].n == 0 then
      if api.fetch(ptr, e.k) ~= 0 then fail(rec, 3) end
    end
  end
  local function live(what)
    if call.in_call == 0 then not_in_call(what, 3) end
  end
  local sname = decl.name
  local w = {}
  w.state = state
  w.settings = frozen(decl.settings or {}, "settings")
  w.area = decl.area
  w.stage = sname
  function w:read(name)
    local e = reads[name]
    if not e then error("stage '" .. sname .. "' reads '" .. tostring(name) .. "' without declaring it (add it to reads)", 2) end
    fetch(e)
    return e.reader
  end
  function w:write(name)
    local e = writes[name]
    if not e then
      if decl.kind ~= "resolver" then error("only a resolver may write properties; '" .. sname .. "' is a " .. decl.kind, 2) end
      error("resolver '" .. sname .. "' writes '" .. tostring(name) .. "' without declaring it (add it to writes)", 2)
    end
    fetch(e)
    return e.writer
  end
  function w:each(name)
    local f, st, c = w:read(name):each()
    return f, st, c
  end
  function w:count(name)
    local n = w:read(name):count()
    return n
  end
  function w:output(name)
    local e = outputs[name]
    if not e then error("derived set '" .. sname .. "' has no output '" .. tostring(name) .. "' (declare it in provides)", 2) end
    fetch(e)
    return e.writer
  end
  function w:derived(set, name)
    local s = derived[set]
    if not s then error("stage '" .. sname .. "' reads derived set '" .. tostring(set) .. "' without declaring it (add it to derived)", 2) end
    local e = s[name]
    if not e then error("derived set '" .. set .. "' has no output '" .. tostring(name) .. "'", 2) end
    fetch(e)
    return e.reader
  end
  function w:name(i) live("w:name") return host.name(handle_, i) end
  function w:find(name) live("w:find") return host.find(handle_, name) end
  function w:alive(i) live("w:alive") return host.alive(handle_, i) end
  function w:emit(type_, fields) live("w:emit") return host.emit(handle_, type_, fields) end
  function w:energy(kind, account, joules) live("w:energy") return host.energy(handle_, kind, account, joules) end
  if decl.functions then
    local by_name = {}
    for _, f in ipairs(decl.functions) do by_name[f.name] = f end
    function w:commands(fname)
      local f = by_name[fname]
      if not f then error("resolver '" .. sname .. "' has no interaction function '" .. tostring(fname) .. "'", 2) end
      return command_iterator(rec, fname, f)
    end
  end
  if decl.contacts then
    function w:contacts(which)
      local kind = contact_kinds[which or "touching"]
      if not kind then error("w:contacts takes 'began', 'ongoing', 'ended' or 'touching'", 2) end
      if call.in_call == 0 then not_in_call("w:contacts") end
      if api.contacts(ptr, kind) ~= 0 then fail(rec, 2) end
      local list, count, epoch = ffi.cast(contact_ptr, call.contacts), call.contact_count, call.epoch
      local j = -1
      return function()
        if call.in_call == 0 or call.epoch ~= epoch then error("contacts can only be read in the call that got them", 2) end
        j = j + 1
        if j >= count then return nil end
        local c = list[j]
        -- The numbers first, then the tables: the host's list is read through.
        local a, b, speed, depth, impulse, total, points, began = c.a, c.b, c.speed, c.depth,
          c.impulse, c.total_impulse, c.points, c.began ~= 0
        local nx, ny, nz, px, py, pz = c.normal.x, c.normal.y, c.normal.z, c.point.x, c.point.y, c.point.z
        return a, b, {
          speed = speed, depth = depth, impulse = impulse, total_impulse = total, points = points,
          began = began, normal = vec3_t(nx, ny, nz), point = vec3_t(px, py, pz),
        }
      end
    end
  end
  if decl.target then
    local t = {}
    local q = command_queue(rec)
    rec.queue = q
    for _, f in ipairs(decl.target.functions) do
      t[f.name] = q.target_function(f.index, f.name, f.kinds, f.record)
    end
    for _, f in ipairs(decl.target.functions) do
      local kind = f.kinds[1]
      if #f.kinds == 1 and (kind == "vec3" or kind == "number") and t[f.name .. "_each"] == nil then
        t[f.name .. "_each"] = bulk_function(rec, f.index, f.name, kind, column_of, f.record)
      end
    end
    w.target = frozen(t, "target '" .. decl.target.name .. "'")
  end
  rec.w = setmetatable(w, { __metatable = "stage view" })
  return rec
end

-- The stage's functions (a table with advance / build / update / apply), and
-- its settings (the mod's defaults may have changed in a reload).
function M.bind(rec, def, settings)
  rec.def = def
  rec.w.settings = frozen(settings, "settings")
end

-- The mod's state table, when it is replaced.
function M.set_state(rec, state) rec.w.state = state end

-- A vec3 or quat in the mod's state, as its doubles, and back
-- (lua/state_codec.hpp): the state codec calls these for cdata values.
function M.cdata_parts(v)
  if is_vec3(v) then return "vec3", v.x, v.y, v.z end
  if is_quat(v) then return "quat", v.w, v.x, v.y, v.z end
  return nil
end
function M.cdata_make(kind, a, b, c, d)
  if kind == "vec3" then return vec3(a, b, c) end
  return quat(a, b, c, d)
end

-- One call of the stage's function `phase`, with the step's numbers.
function M.run(rec, phase, dt, time, step)
  local f = rawget(rec.def, phase)  -- raw: the mod's table may have a metatable
  if f == nil then return end
  local w = rec.w
  w.dt, w.time, w.step = dt, time, step
  if rec.queue then rec.queue.begin() end
  f(w, dt)
  if rec.queue then rec.queue.finish() end
end

return M
