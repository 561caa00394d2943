"""wetclutch: model, identify and control a wet multi-plate clutch in a flywheel-hybrid driveline.

The main entry points:

* :func:`simulate` runs a named scenario and returns a :class:`Result`;
* :class:`Params` / :func:`load_params` hold the validated parameter record;
* :class:`wetclutch.sim.Network` builds any rotational network for the engine.
"""

from . import _jitcache

_jitcache.ensure_consistent()  # before any compiled function loads from the cache

from .errors import ParameterError, SimulationError, WetclutchError  # noqa: E402
from .params import Params  # noqa: E402
from .params import load as load_params  # noqa: E402
from .plant.scenarios import SCENARIOS, Result, simulate  # noqa: E402

__all__ = [
    "SCENARIOS",
    "ParameterError",
    "Params",
    "Result",
    "SimulationError",
    "WetclutchError",
    "load_params",
    "simulate",
]
__version__ = "0.1.0"
