"""`python -m fatswarm`: the `fatswarm` command (the same entry point as the console script)."""

import sys

from fatswarm.deploy.cli import main

if __name__ == "__main__":
    sys.exit(main())
