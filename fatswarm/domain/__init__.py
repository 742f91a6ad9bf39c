"""The domain vocabulary every part of fatswarm shares, below all of them.

Paths, the tolerance model and the one overlap check, the keyed seeded draws with their stream
constants, statuses and exit codes, the message codec and key builders, and the algorithm seam.
It imports only the standard library, numpy and msgpack, and nothing else of fatswarm.
"""
