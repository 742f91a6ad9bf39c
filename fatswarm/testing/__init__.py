"""A test kit for an algorithm of your own: `check_algorithm(ALGORITHM)` holds it to the model's
contract, as scikit-learn's `check_estimator` does for estimators, and raises
`AlgorithmContractError` naming the property broken and the smallest view (or start) that breaks
it. docs/algorithms.md, "Testing your algorithm"; the pytest plugin is fatswarm/pytest_plugin.py.

The kit's modules: report (RULES, CHECKS, the error, Checked), look (a robot's view, answers
compared), subject (the algorithm under test), starts (the views checked), properties (the checks
of one view), shrink (the smallest failing view), params, hunt, and check (`check_algorithm`).
"""

from fatswarm.testing.check import (
    DEFAULT_BUDGET_S,
    DEFAULT_SCHEDULERS,
    DEFAULT_SIZES,
    check_algorithm,
)
from fatswarm.testing.hunt import MIN_SHRINK_S as MIN_SHRINK_S
from fatswarm.testing.hunt import SHOWN_ROUNDS as SHOWN_ROUNDS
from fatswarm.testing.hunt import SHRINK_CHUNK as SHRINK_CHUNK
from fatswarm.testing.hunt import SHRINK_RUNS as SHRINK_RUNS
from fatswarm.testing.look import SWEEP_TOLERANCE as SWEEP_TOLERANCE
from fatswarm.testing.look import TOLERANCE_REL as TOLERANCE_REL
from fatswarm.testing.look import Answer as Answer
from fatswarm.testing.look import Look
from fatswarm.testing.properties import LOOK_PROPERTIES as LOOK_PROPERTIES
from fatswarm.testing.properties import MIRRORED_ROTATIONS as MIRRORED_ROTATIONS
from fatswarm.testing.properties import ROTATIONS as ROTATIONS
from fatswarm.testing.report import CHECKS, RULES, AlgorithmContractError, Checked
from fatswarm.testing.shrink import SHRINK_DECIMALS as SHRINK_DECIMALS
from fatswarm.testing.starts import SHUFFLE_STREAM as SHUFFLE_STREAM
from fatswarm.testing.starts import STARTS_PER_FAMILY as STARTS_PER_FAMILY
from fatswarm.testing.subject import Broken as Broken

# The API is __all__; the names imported `as` themselves (the kit's settings, LOOK_PROPERTIES,
# Answer, Broken) stay importable from here, as from the single module this package replaced.
__all__ = [
    "CHECKS",
    "DEFAULT_BUDGET_S",
    "DEFAULT_SCHEDULERS",
    "DEFAULT_SIZES",
    "RULES",
    "AlgorithmContractError",
    "Checked",
    "Look",
    "check_algorithm",
]
