"""Exceptions that the command line turns into one-line messages, and the reading of text files that raises them."""

import math
import numbers
from contextvars import ContextVar
from pathlib import Path
from typing import Any

import numpy as np


#: the characters at which ``str.splitlines`` breaks a line, each with the escape an error message shows instead
_LINE_BREAKS = str.maketrans({c: repr(c)[1:-1] for c in "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"})


class WetclutchError(Exception):
    """A user-facing error: bad input, a bad file, or a simulation that cannot run.

    Its message is one line: a line break inside a name it quotes from the user's input (a column name, a key of a
    file) shows as its escape (``\\n``)."""

    def __init__(self, *args: object) -> None:
        if len(args) == 1 and isinstance(args[0], str):
            args = (one_line(args[0]),)
        super().__init__(*args)


def one_line(text: str) -> str:
    """``text`` with each line break (any at which ``str.splitlines`` breaks) shown as its escape (``\\n``)."""
    return text.translate(_LINE_BREAKS)


class ParameterError(WetclutchError, ValueError):
    """A parameter is unknown, malformed or out of its physical range."""


class SimulationError(WetclutchError, RuntimeError):
    """The integrator could not complete a run."""


def read_text(path: str | Path, what: str, error: type[WetclutchError] = WetclutchError) -> str:
    """The text (UTF-8) of file ``path``, or ``error`` in one line naming ``what`` and the file: it cannot be read,
    or it is not text (a binary recording given where a TOML file belongs). A byte-order mark (as Windows editors
    write one) is dropped."""
    try:
        return Path(path).read_text(encoding="utf-8-sig")
    except OSError as e:
        raise error(f"cannot read {what} '{path}': {e.strerror or e}") from None
    except UnicodeDecodeError:
        raise error(f"{what} '{path}' is not a text file (UTF-8)") from None


#: whether the running call came from the command line (:mod:`wetclutch.cli` sets it): its one-line errors then name
#: the option (``--t-ref``), a Python caller's the argument (``t_ref``)
COMMAND_LINE: ContextVar[bool] = ContextVar("wetclutch_command_line", default=False)


def named(argument: str, option: str) -> str:
    """What an error calls a value: ``option`` (``--t-ref``) for the command line, else ``argument`` (``t_ref``)."""
    return option if COMMAND_LINE.get() else argument


def shown(value: Any, limit: int = 60) -> str:
    """``value`` shown in an error message: its ``repr`` on one line, cut to ``limit`` characters (an integer of
    hundreds of digits, a long list)."""
    text = repr(value).replace("\n", " ")
    return text if len(text) <= limit else text[:limit - 3] + "..."


def finite_number(value: Any) -> bool:
    """Whether ``value`` (read from a file) is a finite int or float: not a boolean, and not an integer too large
    for a float."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def check_number(value: Any, name: str, unit: str = "") -> float:
    """``value`` as a float if it is a real number (a numpy number will do; a boolean, a string, None or an array
    will not), else one line naming ``name``. NaN and infinities pass: the ranges checked after refuse them."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise WetclutchError(f"{name} must be a number{f' ({unit})' if unit else ''}, not {kind_of(value)} "
                             f"(got {shown(value)})")
    return float(value)


def check_integer(value: Any, name: str) -> int:
    """``value`` as an int if it is a whole number of an integer type (a numpy integer will do; a boolean, a float or
    a string will not), else one line naming ``name``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise WetclutchError(f"{name} must be an integer, not {kind_of(value)} (got {shown(value)})")
    return int(value)


def check_flag(value: Any, name: str) -> bool:
    """``value`` as a bool if it is one (numpy's too), else one line naming ``name`` (a string such as ``"no"`` would
    count as true)."""
    if not isinstance(value, (bool, np.bool_)):
        raise WetclutchError(f"{name} must be True or False, not {kind_of(value)} (got {shown(value)})")
    return bool(value)


def check_instance(value: Any, kind: type | tuple[type, ...], name: str, what: str) -> Any:
    """``value`` if it is a ``kind``, else one line naming ``name`` and saying what it must be (``what``)."""
    if not isinstance(value, kind):
        raise WetclutchError(f"{name} must be {what}, not {kind_of(value)}")
    return value


def kind_of(value: Any) -> str:
    """The kind of ``value`` for an error message: ``a str``, ``an int``, ``None``."""
    if value is None:
        return "None"
    name = type(value).__name__
    return f"{'an' if name[0].lower() in 'aeiou' else 'a'} {name}"
