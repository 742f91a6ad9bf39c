"""The robot: geometry, the paper's algorithm in its private frame, and the agent process."""

# One name per module: from the checkout's root this folder is importable as agent too, and
# agent.x beside fatswarm.agent.x would be two modules of one file.
if __name__ != "fatswarm.agent":
    raise ImportError(f"import fatswarm.agent, not {__name__}")
