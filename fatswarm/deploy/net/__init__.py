"""Networked runs: Zenoh configurations, the router, each part alone and the launcher of them
all."""
