"""Time signals that drive a network: torque sources, clutch capacities.

A signal is described in Python by one of the small classes below and compiled
into one row of a flat float table that the numerical core evaluates with
:func:`value`; this module names the row's slots and alone packs the rows
(:func:`compile_signals`). Discontinuities (a step, the corners
of a ramp) are reported as *breakpoints*: the integrator stops exactly on them
and re-decides the stick/slip modes there, as Modelica does for time events.

All values are SI (N m for torques and capacities, s for times, Hz for
frequencies).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Union

import numpy as np
from numba import njit

#: Width of one row of the compiled signal table.
ROW = 6

CONST, STEP, RAMP, SINE, TABLE, EXTERNAL = range(6)
#: slot 0 of a row is the kind; the others, per kind:
KIND = 0
C_VALUE = 1  # CONST
S_T0, S_BEFORE, S_AFTER = 1, 2, 3  # STEP
R_T0, R_DURATION, R_V0, R_V1 = 1, 2, 3, 4  # RAMP
SN_OFFSET, SN_AMPLITUDE, SN_FREQ, SN_PHASE = 1, 2, 3, 4  # SINE
T_START, T_LENGTH = 1, 2  # TABLE: first sample in the table, number of samples
E_SLOT = 1  # EXTERNAL: index into the external values


def _row(kind: int, slots: dict[int, float]) -> list[float]:
    row = [0.0] * ROW
    row[KIND] = kind
    for k, v in slots.items():
        row[k] = v
    return row


@dataclass(frozen=True)
class Const:
    """A constant value."""

    value: float

    def row(self, table_offset: int) -> list[float]:
        return _row(CONST, {C_VALUE: self.value})

    def breakpoints(self) -> list[float]:
        return []


@dataclass(frozen=True)
class Step:
    """``before`` for ``t < t0``, ``after`` from ``t0`` on (right-continuous)."""

    t0: float
    before: float
    after: float

    def row(self, table_offset: int) -> list[float]:
        return _row(STEP, {S_T0: self.t0, S_BEFORE: self.before, S_AFTER: self.after})

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
        return _row(RAMP, {R_T0: self.t0, R_DURATION: self.duration, R_V0: self.v0, R_V1: self.v1})

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
        return _row(SINE, {SN_OFFSET: self.offset, SN_AMPLITUDE: self.amplitude, SN_FREQ: self.freq_hz,
                           SN_PHASE: self.phase})

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
        return _row(TABLE, {T_START: table_offset, T_LENGTH: self.time.size})

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
        return _row(EXTERNAL, {E_SLOT: self.index})

    def breakpoints(self) -> list[float]:
        return []


Signal = Union[Const, Step, Ramp, Sine, Table, External]


def as_signal(value: Signal | float) -> Signal:
    """Accept a plain number where a signal is expected."""
    if isinstance(value, (int, float, np.floating, np.integer)):
        return Const(float(value))
    return value


#: steps per period of a network's fastest sine signal, by default (:func:`sine_step_limit`)
SINE_STEPS = 10


def sine_step_limit(sig: np.ndarray) -> float:
    """The largest step (s) :func:`wetclutch.sim.network.integrate` takes by default on a network whose compiled
    signal table is ``sig``: a :data:`SINE_STEPS`-th of the shortest sine period, or no limit without sines."""
    freq = [abs(row[SN_FREQ]) for row in sig if int(row[KIND]) == SINE and row[SN_FREQ] != 0.0]
    return 1.0 / (SINE_STEPS * max(freq)) if freq else np.inf


def compile_signals(signals: list[Signal]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Flatten signals into ``(rows, table, breakpoints, ext)`` arrays for the core."""
    rows = np.zeros((max(len(signals), 1), ROW))
    times: list[np.ndarray] = []
    values: list[np.ndarray] = []
    offset = 0
    bps: list[float] = []
    n_ext = 0
    for k, s in enumerate(signals):
        rows[k] = s.row(offset)
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


@njit(cache=True, error_model="numpy", _nrt=False, inline="always")
def value(k, t, left, sig, tab, ext):
    """Value of compiled signal ``k`` at ``t``; ``left`` takes the left limit at a jump.

    ``sig`` and ``tab`` are the rows and table of :func:`compile_signals`, ``ext`` the
    external values.
    """
    # the kinds a closed loop evaluates every step are read in place; the others are one
    # compiled call, as numba copies an inlined body at each of the core's many call sites
    kind = int(sig[k, KIND])
    if kind == CONST:
        return sig[k, C_VALUE]
    if kind == EXTERNAL:
        return ext[int(sig[k, E_SLOT])]
    return _timed_value(k, t, bool(left), sig, tab)


@njit(cache=True, error_model="numpy", _nrt=False)
def _timed_value(k, t, left, sig, tab):
    """Value of a signal that follows time (step, ramp, sine, table)."""
    kind = int(sig[k, KIND])
    if kind == STEP:
        t0 = sig[k, S_T0]
        if t > t0 or (t == t0 and not left):
            return sig[k, S_AFTER]
        return sig[k, S_BEFORE]
    if kind == RAMP:
        t0 = sig[k, R_T0]
        dur = sig[k, R_DURATION]
        if t <= t0:
            return sig[k, R_V0]
        if t >= t0 + dur:
            return sig[k, R_V1]
        return sig[k, R_V0] + (sig[k, R_V1] - sig[k, R_V0]) * (t - t0) / dur
    if kind == SINE:
        return sig[k, SN_OFFSET] + sig[k, SN_AMPLITUDE] * np.sin(2.0 * np.pi * sig[k, SN_FREQ] * t + sig[k, SN_PHASE])
    if kind == TABLE:
        i0 = int(sig[k, T_START])
        n = int(sig[k, T_LENGTH])
        if t <= tab[0, i0]:
            return tab[1, i0]
        if t >= tab[0, i0 + n - 1]:
            return tab[1, i0 + n - 1]
        lo = i0
        hi = i0 + n - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if tab[0, mid] <= t:
                lo = mid
            else:
                hi = mid
        f = (t - tab[0, lo]) / (tab[0, hi] - tab[0, lo])
        return tab[1, lo] + f * (tab[1, hi] - tab[1, lo])
    return 0.0
