"""The `fatswarm` command: lockstep and networked runs, launcher, dashboard, replay."""

# One name per module: from the checkout's root this folder is importable as deploy too, and
# deploy.x beside fatswarm.deploy.x would be two modules of one file.
if __name__ != "fatswarm.deploy":
    raise ImportError(f"import fatswarm.deploy, not {__name__}")
