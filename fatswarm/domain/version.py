"""fatswarm's version, written once: pyproject.toml reads it from here ([tool.setuptools.dynamic]),
so a checkout that was never installed knows it too. The bottom layer holds it, so that every layer
may import it."""

__version__ = "0.1.0"
