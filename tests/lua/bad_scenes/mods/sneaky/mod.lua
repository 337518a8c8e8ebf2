return { name = "sneaky", version = "0.1.0", depends = {} }
