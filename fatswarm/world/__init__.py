"""The world: authority on positions, disc physics with collision detection, run records."""

# One name per module: from the checkout's root this folder is importable as world too, and
# world.x beside fatswarm.world.x would be two modules of one file.
if __name__ != "fatswarm.world":
    raise ImportError(f"import fatswarm.world, not {__name__}")
