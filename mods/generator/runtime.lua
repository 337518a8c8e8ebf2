-- A hand on a crank, as a stage of the world: a part that carries
-- `drive_torque` is turned by that torque, every step, for as long as it
-- carries it (the scene's timeline sets it, changes it, takes it away).
-- Nothing here knows what the part is connected to: on the generator's
-- crank it turns a rotor of magnets past two coils, and the lamp lights
-- because of the induction, not because of anything said here.

mod.property { name = "drive_torque", kind = "vec3", unit = "N m",
               doc = "a torque applied to this part every step (a hand on a crank), world frame" }

-- The rotation that took a part from orientation a to orientation b: its
-- axis times its angle (rad), world frame, the shorter way round.
local function turn(a, b)
  local d = b * quat(a.w, -a.x, -a.y, -a.z)
  local s = d.w < 0 and -1 or 1
  local v = vec3(d.x, d.y, d.z) * s
  local n = v:length()
  if n == 0 then return vec3(0, 0, 0) end
  return v * (2 * math.atan2(n, d.w * s) / n)
end

mod.interaction {
  name = "rigid_body_from_drive",
  doc = "a part carrying drive_torque is turned by it (and the hand's work is booked)",
  reads = { "drive_torque", "orientation" },
  needs = { "drive_torque" },
  target = "rigid_body",
  apply = function(w)
    local torque, ori = w:read("drive_torque"), w:read("orientation")
    -- The hand's work, for the energy books (docs/energy.md): the torque
    -- queued at the last call acted over the rigid body's advance since,
    -- while the part turned from where it was then to where it is now. The
    -- hand is outside the books: its work enters them here (a source) and is
    -- given to the rigid body, which books the same work received ("drive").
    -- Each crank's last orientation and torque are kept by name, as numbers.
    local cranks = w.state.cranks or {}
    w.state.cranks = cranks
    local work = 0
    for i in torque:each() do
      local name, q, t = w:name(i), ori[i], torque[i]
      local c = cranks[name]
      if c then
        work = work + vec3(c[5], c[6], c[7]):dot(turn(quat(c[1], c[2], c[3], c[4]), q))
      end
      cranks[name] = { q.w, q.x, q.y, q.z, t.x, t.y, t.z }
      w.target.add_torque(i, t)
    end
    w:energy("source", "the hand's work", work)  -- it enters the books here
    w:energy("transfer", "drive", -work)
  end,
}

-- A weight on a string wound round a drum (the rotor's hub): the string
-- leaves the drum on its left (-x) side and runs straight to the weight. It
-- is elastic (Hooke, with damping) and goes slack rather than push. Its free
-- length grows by r x the angle the drum turns anticlockwise (string paid
-- out) and shrinks as it turns back (wound up), so a falling weight turns
-- the drum anticlockwise with a torque r T, and the drum's load holds the
-- weight back with the same T. The free length at the start is the distance
-- from the drum's tangent point to the weight (taut, unstretched); the angle
-- turned is kept in the mod's state (a hot reload keeps it; a restored world
-- starts the string afresh from where the weight is).
mod.property { name = "string_drum", kind = "ref", doc = "the part this weight's string is wound on" }
mod.property { name = "string_radius", unit = "m", min = 0, min_exclusive = true,
               doc = "radius the string is wound at on its drum" }
mod.property { name = "string_stiffness", unit = "N/m", min = 0, min_exclusive = true,
               doc = "the string's stiffness, tension per metre of stretch" }
mod.property { name = "string_damping", unit = "N s/m", min = 0,
               doc = "the string's internal damping, tension per m/s of stretching" }

mod.interaction {
  name = "rigid_body_from_string",
  doc = "a weight's string pulls it towards its drum and turns the drum (tension from stretch)",
  reads = { "string_drum", "string_radius", "string_stiffness", "string_damping", "position",
            "velocity", "orientation", "angular_velocity" },
  needs = { "string_drum" },
  target = "rigid_body",
  apply = function(w)
    local drum, radius = w:read("string_drum"), w:read("string_radius")
    local stiffness, damping = w:read("string_stiffness"), w:read("string_damping")
    local pos, vel = w:read("position"), w:read("velocity")
    local ori, spin = w:read("orientation"), w:read("angular_velocity")
    w.state.strings = w.state.strings or {}
    -- The energy books (docs/energy.md). The forces queued at the last call
    -- acted over the rigid body's advance since: their work is taken as the
    -- rigid body takes it, along the weight's move, and along the drum's move
    -- and turn for the force at the tangent (its moment about the drum's
    -- centre). The string gives that work (the transfer "string") out of its
    -- stretch (a store, k s^2 / 2); its damping took c rate^2 over the step (a
    -- sink); what is left is the step's error in the string's own integration
    -- (a sink of either sign, as the rigid body's "integration").
    local given, stored, damped, integration = 0, 0, 0, 0
    for i in drum:each() do
      local d = drum[i]
      if d and pos:has(d) and pos:has(i) then
        local r = radius[i]
        -- At the weight's depth: the weight may hang in front of the drum's plane.
        local tangent = vec3(pos[d].x - r, pos[d].y, pos[i].z)
        local angle = ori[d]:angle_z()
        local s = w.state.strings[i]
        if not s or s.drum ~= d then
          s = { drum = d, length = (pos[i] - tangent):length(), last = angle, turned = 0 }
          w.state.strings[i] = s
        end
        local delta = angle - s.last
        -- angle_z spans (-2 pi, 2 pi] and jumps when the quaternion changes
        -- sign: a step turns the drum far less than half a turn.
        while delta > math.pi do delta = delta - 2 * math.pi end
        while delta < -math.pi do delta = delta + 2 * math.pi end
        s.turned, s.last = s.turned + delta, angle
        local work, lost = 0, 0
        if s.fx then
          local f = vec3(s.fx, s.fy, s.fz)  -- on the weight; the drum had -f at the tangent
          work = f:dot(pos[i] - vec3(s.wx, s.wy, s.wz)) - f:dot(pos[d] - vec3(s.dx, s.dy, s.dz))
                 - vec3(s.ax, s.ay, s.az):cross(f).z * delta
          lost = s.lost
          s.fx = nil
        end
        local span = pos[i] - tangent
        local dist = span:length()
        local stretch = dist - (s.length + r * s.turned)
        local energy = 0
        if stretch > 0 and dist > 0 then
          local u = span / dist
          local rate = vel[i]:dot(u) - r * spin[d].z
          local tension = stiffness[i] * stretch + damping[i] * rate
          energy = 0.5 * stiffness[i] * stretch * stretch
          if tension > 0 then
            local f, arm = u * -tension, tangent - pos[d]
            w.target.add_force(i, f)
            w.target.add_force_at(d, u * tension, tangent)
            s.fx, s.fy, s.fz = f.x, f.y, f.z
            s.wx, s.wy, s.wz = pos[i].x, pos[i].y, pos[i].z
            s.dx, s.dy, s.dz = pos[d].x, pos[d].y, pos[d].z
            s.ax, s.ay, s.az = arm.x, arm.y, arm.z
            s.lost = damping[i] * rate * rate * w.dt
          end
        end
        given, damped, stored = given + work, damped + lost, stored + energy
        integration = integration + (s.energy or 0) - energy - work - lost
        s.energy = energy
      end
    end
    w:energy("store", "the string's stretch", stored)
    w:energy("sink", "the string's damping", damped)
    w:energy("sink", "the string's integration", integration)
    w:energy("transfer", "string", -given)
  end,
}
