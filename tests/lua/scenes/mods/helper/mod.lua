return { name = "helper", version = "1.0.0", depends = { "kit" }, description = "test helper mod" }
