-- Materials of the kit: what a part is made of decides its mass and how it
-- touches other parts. Values are typical handbook figures at room
-- temperature, rounded; a simulation needs their size, not their fourth digit.
--
-- density (kg/m^3): carbon steel 7850, yellow brass 8400-8730, copper 8960,
--   hardwood (oak, beech) 600-900, natural rubber 920-1200.
--   Sources: CRC Handbook of Chemistry and Physics; The Engineering ToolBox,
--   "Metals and Alloys - Densities" and "Wood Species - Densities".
-- friction (dry Coulomb coefficient, sliding on steel): steel 0.42-0.57,
--   brass 0.35-0.44, copper 0.36-0.53, wood on metal 0.2-0.6, rubber on dry
--   hard surfaces 0.6-1.0.
--   Sources: The Engineering ToolBox, "Friction and Friction Coefficients";
--   Serway & Jewett, Physics for Scientists and Engineers, table 5.1.
-- restitution (ratio of rebound to impact speed, a ball dropped about 1 m on
--   a hard floor): hardened steel 0.6-0.9, brass ~0.5, copper ~0.4 (soft,
--   deforms), hardwood ~0.5, a rubber ball 0.75-0.85. Restitution depends on
--   the impact speed and on both bodies; these are the part's own share.
--   Sources: Cross, "The bounce of a ball", Am. J. Phys. 67 (1999);
--   Wikipedia, "Coefficient of restitution" (tables of measured values).
--
-- Later issues add electrical conductivity and magnetic susceptibility here:
-- a material is data, and each physics reads the fields it knows.

return {
  steel  = { density = 7850, friction = 0.5,  restitution = 0.6 },
  brass  = { density = 8500, friction = 0.4,  restitution = 0.5 },
  copper = { density = 8960, friction = 0.45, restitution = 0.4 },
  wood   = { density = 700,  friction = 0.4,  restitution = 0.5 },
  rubber = { density = 1100, friction = 0.9,  restitution = 0.8 },
}
