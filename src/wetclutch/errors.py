"""Exceptions that the command line turns into one-line messages, and the reading of text files that raises them."""

from pathlib import Path


class WetclutchError(Exception):
    """A user-facing error: bad input, a bad file, or a simulation that cannot run."""


class ParameterError(WetclutchError, ValueError):
    """A parameter is unknown, malformed or out of its physical range."""


class SimulationError(WetclutchError, RuntimeError):
    """The integrator could not complete a run."""


def read_text(path: str | Path, what: str, error: type[WetclutchError] = WetclutchError) -> str:
    """The text (UTF-8) of file ``path``, or ``error`` in one line naming ``what`` and the file: it cannot be read,
    or it is not text (a binary recording given where a TOML file belongs)."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as e:
        raise error(f"cannot read {what} '{path}': {e.strerror or e}") from None
    except UnicodeDecodeError:
        raise error(f"{what} '{path}' is not a text file (UTF-8)") from None
