return { name = "extra", version = "0.0.1" }
