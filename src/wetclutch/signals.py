"""Time signals that drive a network: torque sources, clutch capacities.

A signal is described in Python by one of the small classes below and compiled
into one row of a flat float table that the numba core evaluates
(:func:`wetclutch.engine.signal_value`). Discontinuities (a step, the corners
of a ramp) are reported as *breakpoints*: the integrator stops exactly on them
and re-decides the stick/slip modes there, as Modelica does for time events.

All values are SI (N m for torques and capacities, s for times, Hz for
frequencies).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union

import numpy as np

#: Width of one row of the compiled signal table.
ROW = 6

CONST, STEP, RAMP, SINE, TABLE, EXTERNAL = range(6)


@dataclass(frozen=True)
class Const:
    """A constant value."""

    value: float

    def row(self, table_offset: int) -> list[float]:
        return [CONST, self.value]

    def breakpoints(self) -> list[float]:
        return []


@dataclass(frozen=True)
class Step:
    """``before`` for ``t < t0``, ``after`` from ``t0`` on (right-continuous)."""

    t0: float
    before: float
    after: float

    def row(self, table_offset: int) -> list[float]:
        return [STEP, self.t0, self.before, self.after]

    def breakpoints(self) -> list[float]:
        return [self.t0]


@dataclass(frozen=True)
class Ramp:
    """``v0`` until ``t0``, linear to ``v1`` over ``duration``, then ``v1``."""

    t0: float
    duration: float
    v0: float
    v1: float

    def __post_init__(self) -> None:
        if not self.duration > 0.0:
            raise ValueError("Ramp.duration must be > 0 (use Step for a jump)")

    def row(self, table_offset: int) -> list[float]:
        return [RAMP, self.t0, self.duration, self.v0, self.v1]

    def breakpoints(self) -> list[float]:
        return [self.t0, self.t0 + self.duration]


@dataclass(frozen=True)
class Sine:
    """``offset + amplitude * sin(2 pi freq_hz t + phase)``."""

    amplitude: float
    freq_hz: float
    phase: float = 0.0
    offset: float = 0.0

    def row(self, table_offset: int) -> list[float]:
        return [SINE, self.offset, self.amplitude, self.freq_hz, self.phase]

    def breakpoints(self) -> list[float]:
        return []


@dataclass(frozen=True)
class Table:
    """Piecewise-linear interpolation of ``(time, value)`` samples, held at the ends.

    Parameters
    ----------
    time, value
        Samples; ``time`` strictly increasing.
    kinks_are_breakpoints
        Stop the integrator at every sample time. Right for a coarse table with
        real corners; leave off for a densely sampled smooth signal.
    """

    time: np.ndarray
    value: np.ndarray
    kinks_are_breakpoints: bool = False

    def __post_init__(self) -> None:
        t = np.asarray(self.time, dtype=float)
        v = np.asarray(self.value, dtype=float)
        if t.ndim != 1 or t.shape != v.shape or t.size < 1:
            raise ValueError("Table needs 1-D time and value arrays of equal, non-zero length")
        if np.any(np.diff(t) <= 0.0):
            raise ValueError("Table.time must be strictly increasing")
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "value", v)

    def row(self, table_offset: int) -> list[float]:
        return [TABLE, table_offset, self.time.size]

    def breakpoints(self) -> list[float]:
        return list(self.time) if self.kinks_are_breakpoints else []


@dataclass(frozen=True)
class External:
    """A value set from outside between integration calls (zero-order hold).

    Used for co-simulation with a discrete controller: the caller writes
    ``ext[index]`` and then advances the integrator to the next sample.
    """

    index: int
    initial: float = 0.0

    def row(self, table_offset: int) -> list[float]:
        return [EXTERNAL, self.index]

    def breakpoints(self) -> list[float]:
        return []


Signal = Union[Const, Step, Ramp, Sine, Table, External]


def as_signal(value: Signal | float) -> Signal:
    """Accept a plain number where a signal is expected."""
    if isinstance(value, (int, float, np.floating, np.integer)):
        return Const(float(value))
    return value


def compile_signals(signals: list[Signal]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Flatten signals into ``(rows, table, breakpoints, ext)`` arrays for the core."""
    rows = np.zeros((max(len(signals), 1), ROW))
    times: list[np.ndarray] = []
    values: list[np.ndarray] = []
    offset = 0
    bps: list[float] = []
    n_ext = 0
    for k, s in enumerate(signals):
        r = s.row(offset)
        rows[k, : len(r)] = r
        if isinstance(s, Table):
            times.append(s.time)
            values.append(s.value)
            offset += s.time.size
        if isinstance(s, External):
            n_ext = max(n_ext, s.index + 1)
        bps.extend(s.breakpoints())
    table = np.zeros((2, max(offset, 1)))
    if times:
        table[0, :offset] = np.concatenate(times)
        table[1, :offset] = np.concatenate(values)
    ext = np.zeros(max(n_ext, 1))
    for s in signals:
        if isinstance(s, External):
            ext[s.index] = s.initial
    breakpoints = np.unique(np.asarray(bps, dtype=float))
    return rows, table, breakpoints, ext
