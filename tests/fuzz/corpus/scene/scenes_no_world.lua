-- A scene without world{}: defaults everywhere, named after its file.
object { name = "lonely", position = { 0, 1 }, shape = "sphere", radius = 0.1, mass = 1 }
