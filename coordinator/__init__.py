"""Scheduling: who is active each round (fsync, ssync, centralized, scripted); the coordinator."""
