"""What every estimator returns, and the statistics they share.

An :class:`Estimate` is an identified quantity with its standard error and the files
and time windows it came from. The helpers give honest standard errors for filtered
sensor signals (correlated samples) and line up channels that the sensors delayed
differently.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..rig.sensors import DEFAULT_SENSORS
from .recordings import Recording

BAR = 1e5


@dataclass
class Estimate:
    """An identified quantity with its uncertainty and provenance.

    ``value`` and ``se`` (standard error; None where no error model applies) are
    floats or lists of floats in ``unit``; ``sources`` lists ``{file, t_start, t_end}``.
    """

    value: Any
    se: Any
    unit: str
    sources: list[dict[str, Any]] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        return {"value": self.value, "se": self.se, "unit": self.unit, **self.extra, "sources": self.sources}


def source(rec: Recording, t0: float, t1: float) -> dict[str, Any]:
    return {"file": str(rec.path), "t_start": round(float(t0), 4), "t_end": round(float(t1), 4)}


def inflation(resid: np.ndarray) -> float:
    """Variance inflation of a mean or a fit for AR(1)-correlated residuals, ``(1 + rho) / (1 - rho)``.

    Filtered sensor signals sampled faster than their bandwidth are not independent
    samples; ignoring that would understate every standard error.
    """
    if resid.size < 3 or not np.any(resid):
        return 1.0
    rho = float(np.clip(np.corrcoef(resid[:-1], resid[1:])[0, 1], 0.0, 0.99))
    return (1.0 + rho) / (1.0 - rho)


def weighted_mean(values: np.ndarray, ses: np.ndarray) -> tuple[float, float]:
    """Inverse-variance mean and its standard error, widened by the scatter when that exceeds the SEs."""
    w = 1.0 / np.maximum(ses, 1e-12) ** 2
    m = float(np.sum(w * values) / np.sum(w))
    se = float(np.sqrt(1.0 / np.sum(w)))
    if values.size > 1:
        se = max(se, float(np.std(values, ddof=1) / np.sqrt(values.size)))
    return m, se


def robust_std(x: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(x - np.median(x)))) if x.size else 0.0


def aligned(rec: Recording) -> dict[str, np.ndarray]:
    """The recording's channels advanced by their sensor filters' group delay ``sqrt(2) / (2 pi f_c)``."""
    t = rec.t
    out = dict(rec.data)
    for ch, x in rec.data.items():
        spec = DEFAULT_SENSORS.get(ch)
        if spec is not None and spec.cutoff_hz is not None and ch != "oil_temp":
            out[ch] = np.interp(t + np.sqrt(2.0) / (2.0 * np.pi * spec.cutoff_hz), t, x)
    return out


def smooth(x: np.ndarray, n: int) -> np.ndarray:
    return np.convolve(x, np.ones(n) / n, mode="same") if n > 1 else x
