-- World settings the loader must turn into a WorldDef.
world {
  name = "moon",
  description = "low gravity",
  dt = 1 / 120,
  seconds = 2.5,
  plugins = { "rigid_body", "gravity.uniform", "rigid_body_from_gravity" },
  settings = { ["gravity.uniform"] = { g = { 0, -1.62 } } },
  every = { ["gravity.uniform"] = 2 },
}
object { name = "rock", position = { 0, 1 }, shape = "sphere", radius = 0.1, mass = 2 }
