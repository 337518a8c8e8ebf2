-- The magic of rune stones, as four stages of the world (docs/modding.md):
--
--   magic.mana             resolver: mana flows along the links queued for it,
--                          sources refill, lit lift runes spend theirs
--   magic.charge           derived set: how full each stone is (0..1)
--   magic_from_collisions  interaction -> magic.mana: touching stones are linked
--   rigid_body_from_magic  interaction -> rigid_body: a lit lift rune pushes
--                          itself up, against the gravity it feels
--
-- Native physics drives the magic (contacts from the collisions set decide
-- where mana flows) and the magic drives native physics (forces queued on the
-- rigid body). Nothing here knows a scene.

mod.property { name = "rune", kind = "enum", values = { "source", "conduit", "lift" },
               doc = "the rune carved in a stone" }
mod.property { name = "mana", unit = "Mn", min = 0, doc = "mana a rune stone holds" }
mod.property { name = "mana_capacity", unit = "Mn", min = 0, min_exclusive = true,
               doc = "mana a rune stone holds when full" }
mod.property { name = "rune_lit", kind = "bool",
               doc = "a lift rune that filled up and floats until its mana is spent" }

mod.resolver {
  name = "magic.mana",
  doc = "mana flows between linked stones, sources refill, lit lift runes spend",
  reads = { "rune", "mana_capacity" },
  writes = { "mana", "rune_lit" },
  needs = { "rune" },
  functions = { link = { "object" } },  -- link(a, b): a and b touch this step
  settings = {
    conductance = 4,  -- 1/s: share of the difference in fill that flows per second
    regen = 2,        -- Mn/s a source makes
    drain = 1.5,      -- Mn/s a lit lift rune spends
  },
  advance = function(w, dt)
    local s = w.settings
    local mana, lit = w:write("mana"), w:write("rune_lit")
    local cap, rune = w:read("mana_capacity"), w:read("rune")
    for a, b in w:commands("link") do
      -- Like a current between two capacitors: from the fuller to the emptier,
      -- never past level.
      local ca, cb = cap[a], cap[b]
      local fa, fb = mana[a] / ca, mana[b] / cb
      local q = s.conductance * dt * (fa - fb) * math.min(ca, cb)
      local level = (mana[a] + mana[b]) / (ca + cb)
      if q > 0 then q = math.min(q, mana[a] - level * ca) else q = math.max(q, level * cb - mana[b]) end
      mana[a] = mana[a] - q
      mana[b] = mana[b] + q
    end
    for i in rune:each() do
      local r = rune[i]
      if r == "source" then
        mana[i] = math.min(cap[i], mana[i] + s.regen * dt)
      elseif r == "lift" then
        if lit[i] then
          local m = math.max(0, mana[i] - s.drain * dt)
          mana[i] = m
          if m == 0 then
            lit[i] = false
            w:emit("rune_dark", { a = i })
          end
        elseif mana[i] >= 0.99 * cap[i] then
          lit[i] = true
          w.state.flights = (w.state.flights or 0) + 1
          w:emit("rune_lit", { a = i, mana = mana[i] })
        end
      end
    end
  end,
}

mod.derived {
  name = "magic.charge",
  doc = "how full each rune stone is, 0..1",
  reads = { "mana", "mana_capacity" },
  provides = { fill = "number" },
  update = function(w)
    local fill = w:output("fill")
    local mana, cap = w:read("mana"), w:read("mana_capacity")
    for i in mana:each() do
      fill[i] = mana[i] / cap[i]
    end
  end,
}

mod.interaction {
  name = "magic_from_collisions",
  doc = "touching rune stones are linked: mana flows between them",
  reads = { "rune" },
  derived = { "collisions" },
  target = "magic.mana",
  apply = function(w)
    local rune = w:read("rune")
    for a, b in w:contacts("touching") do
      if rune:has(a) and rune:has(b) then w.target.link(a, b) end
    end
  end,
}

mod.interaction {
  name = "rigid_body_from_magic",
  doc = "a lit lift rune pushes itself up: lift x its weight x how full it is",
  reads = { "rune_lit", "mass", "gravity" },
  derived = { "magic.charge" },
  target = "rigid_body",
  settings = { lift = 1.6 },
  apply = function(w)
    local lit, mass, gravity = w:read("rune_lit"), w:read("mass"), w:read("gravity")
    local fill = w:derived("magic.charge", "fill")
    local k = w.settings.lift
    for i in lit:each() do
      if lit[i] and mass:has(i) then
        w.target.add_force(i, gravity[i] * (-k * mass[i] * fill[i]))
      end
    end
  end,
}

-- Handlers run after each step, with the mod's state table.
mod.on("contact_began", function(e, state)
  state.touches = (state.touches or 0) + 1
end)

function mod.on_load(state)
  state.flights = 0
  state.touches = 0
end

function mod.on_reload(state)
  print("magic reloaded: " .. state.flights .. " flights and " .. state.touches .. " touches so far")
end
