"""The `fatswarm` command: lockstep and networked runs, launcher, dashboard, replay."""
