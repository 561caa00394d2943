"""Torque onset: where a signal first rises above a level (shared by calibration and identification)."""

from __future__ import annotations

import numpy as np

TORQUE_ONSET = 0.2  # N m of clutch torque: the onset of torque (about the torque sensor's noise)


def first_crossing(t: np.ndarray, y: np.ndarray, level: float, start: int = 0) -> tuple[float, int, float] | None:
    """Where ``y`` first rises above ``level`` at or after sample ``start``.

    Returns
    -------
    (time, k, f) or None
        The crossing time, linearly interpolated between samples ``k - 1`` and ``k``
        (the first sample above), and the fraction ``f`` of that interval, so that
        another signal ``x`` at the crossing is ``x[k-1] + f (x[k] - x[k-1])``.
        None if ``y`` never rises above ``level`` or already starts above it.
    """
    above = np.flatnonzero(y[start:] > level)
    if above.size == 0 or above[0] == 0:
        return None
    k = start + int(above[0])
    f = float((level - y[k - 1]) / (y[k] - y[k - 1]))
    return float(t[k - 1] + f * (t[k] - t[k - 1])), k, f
