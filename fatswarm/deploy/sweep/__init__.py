"""`fatswarm sweep`: a grid of lock-step runs into a CSV (grid, pool, figures, command)."""
