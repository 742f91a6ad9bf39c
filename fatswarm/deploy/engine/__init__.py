"""The in-process engine: a run's configuration, the lock step and the Python API built on it."""
