-- Materials of the kit: what a part is made of decides its mass, how it
-- touches other parts, whether it conducts, whether a magnet pulls on it and
-- how it rings. Values are typical handbook figures at room temperature,
-- rounded; a simulation needs their size, not their fourth digit. A material
-- is data, and each physics reads the fields it knows.
--
-- density (kg/m^3): carbon steel 7850, pure (soft) iron 7870, yellow brass
--   8400-8730, copper 8960, bell bronze (78 % Cu, 22 % Sn) 8600-8700,
--   hardwood (oak, beech) 600-900, natural rubber 920-1200.
--   Sources: CRC Handbook of Chemistry and Physics; The Engineering ToolBox,
--   "Metals and Alloys - Densities" and "Wood Species - Densities".
-- friction (dry Coulomb coefficient, sliding on steel): steel 0.42-0.57,
--   brass 0.35-0.44, copper 0.36-0.53, bronze 0.3-0.4, wood on metal
--   0.2-0.6, rubber on dry hard surfaces 0.6-1.0.
--   Sources: The Engineering ToolBox, "Friction and Friction Coefficients";
--   Serway & Jewett, Physics for Scientists and Engineers, table 5.1.
--   Pressed wool felt: density 200-400 kg/m^3 (SAE F-grades), friction on
--   wood or metal 0.5-0.7.
-- restitution (ratio of rebound to impact speed, a ball dropped about 1 m on
--   a hard floor): hardened steel 0.6-0.9, brass ~0.5, copper ~0.4 (soft,
--   deforms), hardwood ~0.5, a rubber ball 0.75-0.85; bell bronze is hard and
--   brittle, ~0.6; felt takes a blow and gives nothing back (dampers and
--   buffers are made of it), ~0.05. Restitution depends on the impact speed
--   and on both bodies; these are the part's own share.
--   Sources: Cross, "The bounce of a ball", Am. J. Phys. 67 (1999);
--   Wikipedia, "Coefficient of restitution" (tables of measured values).
--
-- conductive, resistivity (ohm m, 20 C): copper 1.68e-8 (annealed, the IACS
--   standard 1.72e-8), yellow brass 6.4e-8 (28 % IACS), pure iron 9.7e-8,
--   carbon steel 1.4e-7 to 1.7e-7, tin bronze with 20 % tin about 1.5e-7
--   (11 % IACS). Wood, rubber and felt are insulators: no `conductive`.
--   Sources: CRC Handbook, "Electrical resistivity of pure metals"; Copper
--   Development Association, properties of wrought and cast copper alloys.
--   Parts of a conductive material carry conductive = true: touching ones
--   connect (the electricity resolver). A bar is one node, so its own
--   resistance is left out (micro-ohms for a kit bar); resistivity sizes
--   wires and coil windings.
--
-- susceptibility, saturation_magnetization (A/m): ferromagnetic materials
--   only. Annealed pure iron: maximum relative permeability 5000 (Armco iron
--   5000-10000), mu0 Ms = 2.15 T, Ms = 1.71e6 A/m. Carbon steel: a few
--   hundred (hardened less, annealed mild steel up to ~2000), mu0 Ms about
--   2.0 T. A kit part's pull depends far more on its shape than on chi (a bar
--   of aspect ratio 3 is limited to an apparent susceptibility of about 9,
--   whatever chi is; see docs/magnetism.md), so these need no more digits.
--   Sources: Bozorth, Ferromagnetism (1951), ch. 2 and 4; Jiles,
--   Introduction to Magnetism and Magnetic Materials, table of soft
--   magnetic materials. `soft_magnetic = true` (iron only) makes a kit bar of
--   the material soft iron by default; a steel bar is magnetic only when
--   asked (`magnetic = true`), so that a scene with a steel pendulum does not
--   bring the magnetism plugins to life for nothing.
--
-- youngs_modulus (Pa) and loss_factor (material damping eta, every mode's
--   T60 = ln 1000 / (pi f eta)): steel 2.0e11 and ~5e-4, iron 2.1e11, brass
--   1.0e11, copper 1.2e11, bell bronze 1.1e11 and ~1e-4 (bells ring for
--   tens of seconds at their hum), oak along the grain ~1.0e10 and ~1e-2,
--   rubber ~5e7 and ~0.1. Loss factors of real parts depend on how they are
--   held and how they radiate: good to a factor of a few.
--   Sources: CRC Handbook (elastic moduli); Cremer, Heckl & Petersson,
--   Structure-Borne Sound (3rd ed.), table of loss factors; Fletcher &
--   Rossing, The Physics of Musical Instruments, ch. 21 (bells).

-- The kit's own: other mods read materials through kit.material(name).
local materials = {
  steel  = { density = 7850, friction = 0.5,  restitution = 0.6,
             conductive = true, resistivity = 1.5e-7,
             susceptibility = 300, saturation_magnetization = 1.6e6,
             youngs_modulus = 2.0e11, loss_factor = 5e-4 },
  iron   = { density = 7870, friction = 0.5,  restitution = 0.5,
             conductive = true, resistivity = 9.7e-8,
             susceptibility = 5000, saturation_magnetization = 1.71e6, soft_magnetic = true,
             youngs_modulus = 2.1e11, loss_factor = 5e-4 },
  brass  = { density = 8500, friction = 0.4,  restitution = 0.5,
             conductive = true, resistivity = 6.4e-8,
             youngs_modulus = 1.0e11, loss_factor = 1e-3 },
  copper = { density = 8960, friction = 0.45, restitution = 0.4,
             conductive = true, resistivity = 1.68e-8,
             youngs_modulus = 1.2e11, loss_factor = 2e-3 },
  bronze = { density = 8600, friction = 0.35, restitution = 0.6,
             conductive = true, resistivity = 1.5e-7,
             youngs_modulus = 1.1e11, loss_factor = 1e-4 },
  wood   = { density = 700,  friction = 0.4,  restitution = 0.5,
             youngs_modulus = 1.0e10, loss_factor = 1e-2 },
  rubber = { density = 1100, friction = 0.9,  restitution = 0.8,
             youngs_modulus = 5e7, loss_factor = 0.1 },
  felt   = { density = 300,  friction = 0.6,  restitution = 0.05 },
}

return alloy.per_mod(function(mod)
  if mod == "kit" then return materials end
end)
