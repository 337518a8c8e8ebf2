-- Joints of the kit: hinges (rotation about the play area's normal), pins
-- (a part held to the play area) and glue (two parts fixed together).
-- A missing second body means the play area itself.
local joints = {}

local Z = { 0, 0, 1 }  -- hinges turn in the plane: about +z

local function hinge_props(a, b, anchor, friction, limits)
  local p = { joint = "hinge", body_a = a, body_b = b, anchor = anchor, axis = Z }
  if friction then p.joint_friction = friction end
  if limits then
    p.limit_low, p.limit_high = limits[1], limits[2]
  end
  return p
end

joints.hinge = {
  doc = "a hinge joining part a to part b (or to the play area) about a point",
  args = {
    { "a", "object", required = true, doc = "the part that turns" },
    { "b", "object", doc = "the other part; absent: the play area" },
    { "anchor", "vec", required = true, doc = "the hinge point {x, y}, m" },
    { "friction", "nonnegative", doc = "friction torque of the hinge, N m" },
    { "limits", "range", doc = "{low, high} angles, rad" },
  },
  build = function(a)
    return hinge_props(a.a, a.b, a.anchor, a.friction, a.limits)
  end,
}

joints.pin = {
  doc = "a pin through a part into the play area: the part turns about it (or, fixed, cannot move)",
  args = {
    { "part", "object", required = true },
    { "at", "vec", doc = "the pin's point {x, y}, m; default: the part's centre" },
    { "fixed", "boolean", default = false, doc = "true: the part cannot turn either" },
    { "friction", "nonnegative", doc = "friction torque of the pin, N m" },
  },
  build = function(a, kit)
    local at = a.at or kit.placed(a.part)
    if not at then
      kit.fail(a.name, "kit.pin needs 'at': '" .. a.part .. "' was not made by the kit, so its centre is unknown")
    end
    if a.fixed then
      return { joint = "fixed", body_a = a.part, anchor = at }
    end
    return hinge_props(a.part, nil, at, a.friction, nil)
  end,
}

joints.glue = {
  doc = "glue: two parts fixed together so that they move as one",
  args = {
    { "a", "object", required = true },
    { "b", "object", required = true },
  },
  build = function(a, kit)
    local at = kit.placed(a.a)
    return { joint = "fixed", body_a = a.a, body_b = a.b, anchor = at }
  end,
}

joints.spring = {
  doc = "a spring with a damper from a point of part a to a point of part b (or of the play area)",
  args = {
    { "a", "object", required = true, doc = "the part at its first end" },
    { "b", "object", doc = "the part at its other end; absent: the play area" },
    { "at_a", "vec", doc = "its end on a, from a's centre in a's own frame {x, y}, m; default: the centre" },
    { "at_b", "vec", doc = "its end on b, from b's centre in b's frame; with no b, a point of the play area, m" },
    { "stiffness", "positive", required = true, doc = "N/m" },
    { "rest_length", "nonnegative", required = true, doc = "its length with no force, m" },
    { "damping", "nonnegative", default = 0, doc = "the damper, N s/m" },
  },
  build = function(a, kit)
    if not a.b and not a.at_b then
      kit.fail(a.name, "kit.spring needs 'b' or 'at_b' (a point of the play area) for its other end")
    end
    -- rigid_body_from_springs refuses one too stiff for the step (by name).
    return {
      spring_a = a.a, spring_b = a.b,
      spring_anchor_a = a.at_a or { 0, 0 }, spring_anchor_b = a.at_b or { 0, 0 },
      spring_stiffness = a.stiffness, spring_rest_length = a.rest_length, spring_damping = a.damping,
    }
  end,
}

-- kit.rope, not kit.string: the hoist's drum string (mods/hoist) owns that name.
joints.rope = {
  doc = "a string or rope from a point of part a to a point of part b (or of the play area): it pulls only when taut",
  args = {
    { "a", "object", required = true, doc = "the part at its first end" },
    { "b", "object", doc = "the part at its other end; absent: the play area" },
    { "at_a", "vec", doc = "its end on a, from a's centre in a's own frame {x, y}, m; default: the centre" },
    { "at_b", "vec", doc = "its end on b, from b's centre in b's frame; with no b, a point of the play area, m" },
    { "length", "positive", required = true, doc = "its length, m: longer than the ends' distance, it hangs slack" },
    -- A string is a stiff spring that cannot push: a little stretch under
    -- load (a 37 g ball: 1.2 mm), stable at 1/240 s on parts down to 10 g.
    { "stiffness", "positive", default = 300, doc = "N/m of stretch past its length" },
    { "damping", "nonnegative", default = 0.2, doc = "of its stretching, N s/m" },
  },
  build = function(a, kit)
    if not a.b and not a.at_b then
      kit.fail(a.name, "kit.rope needs 'b' or 'at_b' (a point of the play area) for its other end")
    end
    -- rigid_body_from_springs makes it a string (spring_slack) and refuses
    -- one too stiff for the step on light parts (by name).
    return {
      spring_a = a.a, spring_b = a.b,
      spring_anchor_a = a.at_a or { 0, 0 }, spring_anchor_b = a.at_b or { 0, 0 },
      spring_stiffness = a.stiffness, spring_rest_length = a.length, spring_damping = a.damping,
      spring_slack = true,
    }
  end,
}

-- The kit's own: other mods use these parts through `require "kit"`.
return alloy.per_mod(function(mod)
  if mod == "kit" then return joints end
end)
