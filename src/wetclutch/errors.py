"""Exceptions that the command line turns into one-line messages."""


class WetclutchError(Exception):
    """A user-facing error: bad input, a bad file, or a simulation that cannot run."""


class ParameterError(WetclutchError, ValueError):
    """A parameter is unknown, malformed or out of its physical range."""


class SimulationError(WetclutchError, RuntimeError):
    """The integrator could not complete a run."""
