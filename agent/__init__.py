"""The robot: geometry, the paper's algorithm in the robot's private frame, and the agent process."""
