"""Scheduling: who is active each round (fsync, ssync, centralized, scripted); the coordinator."""

# One name per module: from the checkout's root this folder is importable as coordinator too, and
# coordinator.x beside fatswarm.coordinator.x would be two modules of one file.
if __name__ != "fatswarm.coordinator":
    raise ImportError(f"import fatswarm.coordinator, not {__name__}")
