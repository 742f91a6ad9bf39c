"""The world: authority on positions, disc physics with collision detection, run records."""
