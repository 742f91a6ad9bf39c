"""`fatswarm hunt`: a search for counterexamples, shrunk and saved (search, pool, command)."""
