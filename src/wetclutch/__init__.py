"""wetclutch: model, identify and control a wet multi-plate clutch in a flywheel-hybrid driveline.

The main entry points:

* :func:`simulate` runs a named scenario and returns a :class:`Result`;
* :class:`Params` / :func:`load_params` hold the validated parameter record;
* :class:`wetclutch.network.Network` builds any rotational network for the engine.
"""

from .errors import ParameterError, SimulationError, WetclutchError
from .params import Params
from .params import load as load_params
from .scenarios import SCENARIOS, Result, simulate

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
