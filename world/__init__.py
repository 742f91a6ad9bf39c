"""The world: authority on positions, disc physics with continuous collision detection, run records."""
