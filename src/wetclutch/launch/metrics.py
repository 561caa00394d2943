"""Figures of a torque response and the launch requirements.

Definitions (all from the measured axle torque ``T_r``, as a test engineer would
evaluate a rig recording; ``t_req`` is the request time, ``t_sync`` the
synchronisation):

steady window
    ``[t_req + 0.3 s, min(t_req + 1.3 s, t_sync - 0.1 s)]``: after the response,
    before synchronisation ends the slip phase. Shorter than :data:`MIN_WINDOW`
    (a request so large that the clutch synchronises at once): no steady state,
    the steady-state requirement fails.
static value ``T_ss``
    Mean of ``T_r`` over the steady window.
``steady_state_error_pct``
    ``|T_ss - mean(t_ref)| / mean(t_ref) * 100`` over the steady window.
``t95_s``
    From the request until ``T_r`` first reaches 95 % of ``T_ss`` (inf if never).
    For a request that is not a step (ramp, profile file) the clock starts when the
    request itself first reaches 95 % of its mean over the steady window, so that
    the figure is the response's lag, not the profile's own rise time.
``overshoot_pct``
    ``(max T_r before t_sync - T_ss) / T_ss * 100``, at least 0; ``T_r`` smoothed
    over :data:`SMOOTH` first, so that sensor noise does not count.
``jerk_max``
    Largest rate of change of the smoothed ``T_r`` (N m/s) between the request
    and synchronisation: the vehicle's jerk is this over its inertia.
robustness
    The launch's response compared with the nominal launch (design rig, design
    oil temperature, same request): ``t95`` within :data:`ROBUST_DT95` of the
    nominal's and an overshoot at most :data:`ROBUST_OVERSHOOT` percentage points
    above the nominal's (less overshoot is no deterioration).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

REQ_ESS_PCT = 10.0
REQ_T95_S = 0.2
ROBUST_DT95 = 0.05  # s
ROBUST_OVERSHOOT = 10.0  # percentage points
MIN_WINDOW = 0.1  # s
SMOOTH = 0.01  # s


@dataclass(frozen=True)
class Response:
    """Figures of one torque response (see the module docstring); NaN where undefined."""

    T_ss: float
    steady_state_error_pct: float
    t95_s: float
    overshoot_pct: float
    jerk_max: float
    window: tuple[float, float]

    @classmethod
    def empty(cls) -> Response:
        return cls(np.nan, np.nan, np.nan, np.nan, np.nan, (np.nan, np.nan))


def _smooth(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    n = max(1, int(round(SMOOTH / np.median(np.diff(t))))) if t.size > 1 else 1
    if n == 1 or y.size < n:
        return y
    c = np.cumsum(np.concatenate([[0.0], y]))
    out = y.copy()
    out[n - 1:] = (c[n:] - c[:-n]) / n  # trailing mean: causal, like a filter
    return out


def response(t: np.ndarray, T_r: np.ndarray, t_ref: np.ndarray, t_req: float, t_sync: float | None) -> Response:
    """Figures of the response of ``T_r`` to the request ``t_ref`` made at ``t_req``."""
    t_end = t[-1] if t_sync is None else t_sync
    w0, w1 = t_req + 0.3, min(t_req + 1.3, t_end - 0.1)
    if w1 - w0 < MIN_WINDOW:
        return Response(np.nan, np.nan, np.nan, np.nan, np.nan, (w0, w1))
    win = (t >= w0) & (t <= w1)
    T_ss = float(np.mean(T_r[win]))
    ref = float(np.mean(t_ref[win]))
    if not ref > 0.0:  # no torque asked for over the window: no relative error, no 95 % level
        return Response(np.nan, np.nan, np.nan, np.nan, np.nan, (w0, w1))
    ess = abs(T_ss - ref) / ref * 100.0
    after = t >= t_req
    reached = np.flatnonzero(after & (T_r >= 0.95 * T_ss))
    asked = np.flatnonzero(after & (t_ref >= 0.95 * ref))
    t_start = float(t[asked[0]]) if asked.size else t_req
    t95 = float(t[reached[0]] - t_start) if reached.size and T_ss > 0 else np.inf
    slip = after & (t < t_end)
    y = _smooth(t, T_r)
    overshoot = max(0.0, (float(np.max(y[slip])) - T_ss) / T_ss * 100.0) if T_ss > 0 else np.nan
    rate = np.abs(np.diff(y)) / np.diff(t)
    jerk = float(np.max(rate[slip[1:]])) if np.any(slip[1:]) else np.nan
    return Response(T_ss, ess, t95, overshoot, jerk, (w0, w1))


def requirements(r: Response, nominal: Response) -> dict[str, bool]:
    """Pass/fail of the three requirements: steady-state error, response time, robustness."""
    robust = (np.isfinite(nominal.t95_s) and np.isfinite(r.t95_s)
              and abs(r.t95_s - nominal.t95_s) <= ROBUST_DT95
              and r.overshoot_pct - nominal.overshoot_pct <= ROBUST_OVERSHOOT)
    return {
        "steady_state_error": bool(r.steady_state_error_pct <= REQ_ESS_PCT),
        "response_time": bool(r.t95_s < REQ_T95_S),
        "robustness": bool(robust),
    }


def summary(r: Response, nominal: Response, slip_energy: float, t_sync: float | None) -> dict[str, Any]:
    """The ``summary.json`` figures of a launch."""
    req = requirements(r, nominal)
    d = asdict(r)
    d.pop("window")
    return {
        **{k: (None if not np.isfinite(v) else float(v)) for k, v in d.items()},
        "steady_window_s": list(r.window),
        "slip_energy_J": slip_energy,
        "t_sync_s": t_sync,
        "nominal_t95_s": None if not np.isfinite(nominal.t95_s) else nominal.t95_s,
        "nominal_overshoot_pct": None if not np.isfinite(nominal.overshoot_pct) else nominal.overshoot_pct,
        "requirements": req,
        "all_pass": all(req.values()),
    }
