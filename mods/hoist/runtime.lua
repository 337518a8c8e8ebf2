-- A string wound on a drum and tied to a load, as two stages of the world:
--
--   strings.winding          resolver: the drum's turning winds string in
--                            (anticlockwise) or pays it out: the free length
--                            changes by the drum's radius times its turn
--   rigid_body_from_strings  interaction -> rigid_body: the string's
--                            elastic tension pulls the load towards the
--                            drum, and the drum, at the point where the
--                            string leaves it, towards the load
--
-- The string is elastic (tension = EA strain + damping strain rate, over
-- its free length) and pulls only: slack, it does nothing. It leaves the drum
-- on the tangent from the load, on the side where an anticlockwise turn
-- takes it in. Nothing here knows what the string is used for; it meets no
-- other part (it runs behind the play area's parts, as a string on an axle
-- behind a rotor does).

mod.property { name = "string_drum", kind = "ref", doc = "the part a string is wound on" }
mod.property { name = "string_load", kind = "ref", doc = "the part tied to a string's free end" }
mod.property { name = "string_radius", unit = "m", min = 0, min_exclusive = true,
               doc = "the radius of the drum where the string lies" }
mod.property { name = "string_free_length", unit = "m", min = 0,
               doc = "a string's free length, unstretched: from the drum to the load" }
mod.property { name = "string_stiffness", unit = "N", min = 0, min_exclusive = true,
               doc = "EA: a string's tension per unit strain" }
mod.property { name = "string_damping", unit = "N s", min = 0,
               doc = "a string's tension per unit strain rate" }

mod.resolver {
  name = "strings.winding",
  doc = "a drum turning anticlockwise winds its string in, clockwise pays it out",
  reads = { "string_drum", "string_radius", "angular_velocity" },
  writes = { "string_free_length" },
  needs = { "string_drum" },
  advance = function(w, dt)
    local drum, radius, spin = w:read("string_drum"), w:read("string_radius"), w:read("angular_velocity")
    local free = w:write("string_free_length")
    for i in drum:each() do
      local d = drum[i]
      if d then
        -- A string wound to the drum stays there: it cannot wind further
        -- than its end (the load then rides on the drum).
        free[i] = math.max(0, free[i] - radius[i] * spin[d].z * dt)
      end
    end
  end,
}

mod.interaction {
  name = "rigid_body_from_strings",
  doc = "a taut string pulls its load towards its drum and the drum towards the load",
  reads = { "string_drum", "string_load", "string_radius", "string_free_length", "string_stiffness",
            "string_damping", "position", "velocity", "angular_velocity" },
  target = "rigid_body",
  apply = function(w)
    local drum, load = w:read("string_drum"), w:read("string_load")
    local radius, free = w:read("string_radius"), w:read("string_free_length")
    local ea, damping = w:read("string_stiffness"), w:read("string_damping")
    local pos, vel, spin = w:read("position"), w:read("velocity"), w:read("angular_velocity")
    for i in drum:each() do
      local d, l = drum[i], load[i]
      if d and l then
        local c, p, r = pos[d], pos[l], radius[i]
        local qx, qy = p.x - c.x, p.y - c.y
        local D2 = qx * qx + qy * qy
        if D2 > r * r then
          -- The tangent point: at the angle beta = acos(r / D) either side
          -- of the line to the load; the one where the surface of a drum
          -- turning anticlockwise moves away from the load (winds in).
          local D = math.sqrt(D2)
          local ux, uy = qx / D, qy / D
          local cb, sb = r / D, math.sqrt(1 - (r / D) ^ 2)
          local tx, ty = cb * ux - sb * uy, sb * ux + cb * uy  -- unit, rotated by +beta
          if (-ty) * (r * tx - qx) + tx * (r * ty - qy) <= 0 then
            tx, ty = cb * ux + sb * uy, -sb * ux + cb * uy     -- the other side
          end
          local px, py = c.x + r * tx, c.y + r * ty            -- where it leaves the drum
          local dx, dy = p.x - px, p.y - py
          local len = math.sqrt(dx * dx + dy * dy)             -- its free part, stretched
          local L = free[i]
          if len > L and L > 0 then
            -- The stretch's rate: the tangent's length grows as q.v / len
            -- (d(len^2) = d(D^2)), and the drum winds in r w a second.
            local vp, vc = vel[l], vel[d]
            local rate = (qx * (vp.x - vc.x) + qy * (vp.y - vc.y)) / len + r * spin[d].z
            local tension = (ea[i] * (len - L) + damping[i] * rate) / L
            if tension > 0 then
              local f = vec3(dx / len * tension, dy / len * tension, 0)
              w.target.add_force(l, -f)
              w.target.add_force_at(d, f, vec3(px, py, c.z))
            end
          end
        end
      end
    end
  end,
}
