"""The robot: geometry, the paper's algorithm in its private frame, and the agent process."""
