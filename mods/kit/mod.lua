-- The construction kit (paper section 4): parts that lie on the flat play
-- area and may be pinned to it. Physics stays 3D; kit bodies are held to the
-- z = 0 plane (planar = true).
return {
  name = "kit",
  version = "0.1.0",
  description = "Construction-kit parts: materials, bars, disks, floors, walls, pins, hinges, glue, batteries, contacts, wires, coils, magnets, armatures, bells",
  depends = {},
}
