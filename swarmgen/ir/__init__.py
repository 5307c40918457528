"""The intermediate representation: nodes, expressions, the builder from the raw model, lookups."""
