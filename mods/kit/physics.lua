-- Formulas the kit's parts share: from a part's size and material to the
-- numbers a resolver wants (a coil's inductance, a magnet's pole strength).
-- SI units throughout.
local physics = {}

physics.mu0 = 1.25663706212e-6  -- vacuum permeability, N/A^2

--- The magnetism resolver puts a bar's poles 0.85 of its length apart (the
--- "magnetic length" of a bar magnet); parts that compute pole strengths use
--- the same figure (docs/magnetism.md).
physics.magnetic_length_ratio = 0.85

--- Axial demagnetising factor of a spheroid of aspect ratio p = length /
--- diameter (Osborn 1945): 1/3 for a sphere, -> 0 for a needle. The same
--- formula as the magnetism resolver's.
function physics.demagnetizing_factor(p)
  local e = p - 1
  if math.abs(e) < 1e-3 then return 1 / 3 - 4 / 15 * e end
  if p > 1 then
    local s = math.sqrt(p * p - 1)
    return (p / s * math.log(p + s) - 1) / (p * p - 1)
  end
  local s = math.sqrt(1 - p * p)
  return (1 - p / s * math.acos(p)) / (1 - p * p)
end

--- Apparent susceptibility of a rod of intrinsic susceptibility chi and
--- aspect ratio p: chi / (1 + N chi). Shape, not material, limits it.
function physics.apparent_susceptibility(chi, p)
  return chi / (1 + physics.demagnetizing_factor(p) * chi)
end

--- Diameter of the circle with the area of a w x h rectangle.
function physics.equivalent_diameter(w, h)
  return math.sqrt(4 * w * h / math.pi)
end

--- Resistance of a round wire, ohm.
function physics.wire_resistance(resistivity, length, diameter)
  return resistivity * length / (math.pi * diameter * diameter / 4)
end

return physics
