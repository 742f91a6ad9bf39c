"""Scheduling: who is active in each round (fsync, ssync, centralized, scripted) and the coordinator process."""
