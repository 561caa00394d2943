"""Figures of a torque response and the launch requirements.

Definitions (all from the measured axle torque ``T_r``, as a test engineer would
evaluate a rig recording; ``t_req`` is the request time, ``t_sync`` the
synchronisation):

steady window
    ``[t_req + STEADY_START, min(t_req + STEADY_END, t_sync - 0.1 s)]``: after the response,
    before synchronisation ends the slip phase; one definition for every controller.
    Where an early lock-up leaves less than :data:`MIN_WINDOW` of it (a light primary
    flywheel, an overdrive ratio, a large request), the last :data:`MIN_WINDOW` before
    ``t_sync - 0.1 s``, if that starts no earlier than :data:`REQ_T95_S` after the request,
    when the response time allowed is over. Shorter still (a clutch that synchronises at
    once): no steady state, the steady-state requirement fails.
static value ``T_ss``
    Mean of ``T_r`` over the steady window.
``steady_state_error_pct``
    ``|T_ss - mean(t_ref)| / mean(t_ref) * 100`` over the steady window.
``t95_s``
    The study's response time: from the request until ``T_r`` first reaches 95 % of ``T_ss``
    (inf if never). For a request that is not a step (ramp, profile file) the clock starts
    when the request itself first reaches 95 % of its mean over the steady window, so that
    the figure is the response's lag, not the profile's own rise time.
``t95_settled_s``
    The response time the requirement judges: from the same start until ``T_r`` (centred
    average over :data:`SETTLE_SMOOTH`, so that sensor noise on a small request does not count)
    enters the band above 95 % of ``T_ss`` for the last time before :data:`STEADY_START` after
    that start, where the steady window begins for a step (a torque still below the band
    then: its first entry after it), and never before ``t95_s``. A response that makes a
    first hump to 90-96 % of the request, dips and rises again has one value whatever side of
    95 % the hump ends on; the first crossing (``t95_s``) jumps between the hump and the
    second rise. A wander inside the steady window is judged by the steady-state error and
    the ripple, which change with it continuously.
``overshoot_pct``
    ``(max T_r between the request and the end of the steady window - T_ss) / T_ss * 100``,
    at least 0; ``T_r`` smoothed over :data:`SMOOTH` first, so that sensor noise does not count.
``ripple_pct``
    RMS of ``T_r`` about ``T_ss`` over the steady window, in % of ``T_ss``, with the sensor's noise taken
    out (its variance subtracted from the mean square: the sensor's where it is known, as in a simulated
    launch, else estimated from the standby by :func:`noise_std`): a sustained
    oscillation through the slip phase fails even when its mean is right, whatever its frequency (a
    valve in a 110 Hz limit cycle as much as a clutch output ringing at 8 Hz), while the noise of a
    small request's reading does not count.
``oscillation_pct``
    The same about the least-squares straight line of ``T_r`` over the steady window: the part of the
    ripple that oscillates rather than drifts (a torque that sags as the clutch reaches its capacity
    near synchronisation, or still rises, has a ripple but no oscillation). Reported, not judged: the
    ripple is.
``jerk_max``
    Largest rate of change of the smoothed ``T_r`` (N m/s) between the request
    and synchronisation: the vehicle's jerk is this over its inertia.
``contact_s``
    From the request to the plates' first contact (the simulation's true clutch torque, which a rig does not
    measure): positive where the fill was not complete when torque was asked for.
``input_at_max_pct``
    Share of the steady window's samples (%) with the valve input at the top of its range while
    ``T_r`` is short of the request: the controller asks for all the valve gives and the torque
    still falls short, so the clutch is at or beyond its capacity there (supply pressure, friction,
    CVT ratio and request); a dithered input at the top reaches it in half the samples. (An input at
    the top with the torque above the request is a controller wound up, not a capacity.)
``creep_Nm``
    Mean of ``T_r`` over the last :data:`CREEP_WINDOW` before the request: what the clutch
    in standby pushes into a waiting vehicle.
``standby_peak_Nm``
    Largest mean of ``T_r`` over any :data:`PEAK_WINDOW` before the request: the jolt of
    the plates' first contact (reported, not judged).
robustness
    The launch's response compared with the nominal launch (the design on its own plant,
    that plant's oil temperature, same request, interpolated between request levels:
    :func:`wetclutch.launch.loop.nominal_grid`): ``t95_settled`` at most :data:`ROBUST_DT95`
    later than the nominal's, an overshoot at most :data:`ROBUST_OVERSHOOT` percentage points
    above the nominal's, and a ripple at most :data:`REQ_RIPPLE_PCT`. A faster response, as
    less overshoot, is no deterioration: where the nominal launch is itself at the clutch's
    capacity (a clutch whose own CVT ratio is an overdrive, at the largest requests), a
    launch at a lower ratio, with the capacity the nominal lacks, answers faster than it.
standby
    ``creep_Nm`` at most :data:`REQ_CREEP_NM`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

REQ_ESS_PCT = 10.0
REQ_T95_S = 0.2
ROBUST_DT95 = 0.05  # s
ROBUST_OVERSHOOT = 10.0  # percentage points
REQ_RIPPLE_PCT = 5.0
REQ_CREEP_NM = 10.0
STEADY_START, STEADY_END = 0.3, 1.3  # s after the request
MIN_WINDOW = 0.1  # s
SMOOTH = 0.01  # s
SETTLE_SMOOTH = 0.02  # s: centred average for the band of the settled response time (sensor noise of a small request)
CREEP_WINDOW = 0.2  # s
PEAK_WINDOW = 0.1  # s
#: the requirements, in the order reports list them
REQUIREMENTS = ("steady_state_error", "response_time", "robustness", "standby")


@dataclass(frozen=True)
class Response:
    """Figures of one torque response (see the module docstring); NaN where undefined."""

    T_ss: float
    steady_state_error_pct: float
    t95_s: float
    t95_settled_s: float
    overshoot_pct: float
    ripple_pct: float
    oscillation_pct: float
    jerk_max: float
    creep_Nm: float
    standby_peak_Nm: float
    window: tuple[float, float]

    @classmethod
    def empty(cls, standby: tuple[float, float] = (np.nan, np.nan),
              window: tuple[float, float] = (np.nan, np.nan)) -> Response:
        return cls(np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, *standby, window)


def _centred(t: np.ndarray, y: np.ndarray, width: float) -> np.ndarray:
    """Centred moving average over ``width`` (no lag: the band check must not shift the time it finds)."""
    n = max(1, int(round(width / np.median(np.diff(t))))) if t.size > 1 else 1
    if n == 1 or y.size < n:
        return y
    return np.convolve(y, np.ones(n) / n, mode="same")


def _smooth(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    n = max(1, int(round(SMOOTH / np.median(np.diff(t))))) if t.size > 1 else 1
    if n == 1 or y.size < n:
        return y
    c = np.cumsum(np.concatenate([[0.0], y]))
    out = y.copy()
    out[n - 1:] = (c[n:] - c[:-n]) / n  # trailing mean: causal, like a filter
    return out


def noise_std(t: np.ndarray, T_r: np.ndarray, t_req: float) -> float:
    """Standard deviation of the reading's white noise, from the last :data:`CREEP_WINDOW` before the request:
    the median of ``|dT_r|`` from sample to sample over ``0.6745 sqrt(2)`` (the differences of a white noise of
    deviation ``s`` are normal with deviation ``s sqrt(2)``, and the median of their magnitude is 0.6745 times
    that). The waiting clutch's torque changes slowly, so the differences are the noise's, and a jolt of the plates'
    contact moves the median little. 0 without samples there."""
    y = T_r[(t < t_req) & (t >= t_req - CREEP_WINDOW)]
    if y.size < 3:
        return 0.0
    return float(np.median(np.abs(np.diff(y))) / (0.6745 * np.sqrt(2.0)))


def _rms_less_noise(e: np.ndarray, noise: float) -> float:
    """RMS of ``e`` with the noise's variance taken out of its mean square (0 where the noise is all of it)."""
    return float(np.sqrt(max(np.mean(e ** 2) - noise ** 2, 0.0)))


def ripple_pct(y: np.ndarray, noise: float = 0.0) -> float:
    """RMS of ``y`` about its mean, with the noise's variance (standard deviation ``noise``) taken out, in % of the
    mean: the ripple of a torque over the judged window."""
    mean = float(np.mean(y))
    return _rms_less_noise(y - mean, noise) / mean * 100.0


def standby(t: np.ndarray, T_r: np.ndarray, t_req: float) -> tuple[float, float]:
    """(creep, peak): the mean of ``T_r`` over the last :data:`CREEP_WINDOW` before the request, the largest
    :data:`PEAK_WINDOW` mean before it."""
    before = t < t_req
    y = T_r[before]
    if y.size == 0:
        return np.nan, np.nan
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    creep = float(np.mean(y[t[before] >= t_req - CREEP_WINDOW]))
    n = max(1, int(round(PEAK_WINDOW / dt)))
    if y.size < n:
        return creep, float(np.mean(y))
    c = np.cumsum(np.concatenate([[0.0], y]))
    return creep, float(np.max((c[n:] - c[:-n]) / n))


def _settled(t: np.ndarray, T_r: np.ndarray, after: np.ndarray, T_ss: float, w0: float, w1: float,
             t_start: float, t_reached: float) -> float:
    """The settled response time: the last entry into the band above 95 % of ``T_ss`` (``T_r`` smoothed, so that
    noise does not count) before the response phase ends at ``w0`` (``t_reached`` if it never left it); a torque
    still below the band there enters it later (its first entry after ``w0``, inf if never before ``w1``). A slow
    wander of the torque inside the steady window is the steady state's (its mean error and ripple), not the
    response's: were it judged here, a sag to 94.9 % of ``T_ss`` late in the window would move the response time
    by most of a second against one to 95.1 %."""
    band = _centred(t, T_r, SETTLE_SMOOTH) >= 0.95 * T_ss
    below = np.flatnonzero(after & (t <= w0) & ~band)
    if below.size == 0:
        return max(t_reached - t_start, 0.0)
    i = below[-1] + 1
    if i < t.size and t[i] <= w0:
        return float(t[i] - t_start)
    later = np.flatnonzero((t > w0) & (t <= w1) & band)
    return float(t[later[0]] - t_start) if later.size else np.inf


def judged_window(w0: float, w1: float) -> bool:
    """Whether a steady window ``[w0, w1]`` (s) is long enough to judge: :data:`MIN_WINDOW` or more (an early
    lock-up's window of exactly that length, less the rounding of its ends, included)."""
    return w1 - w0 >= MIN_WINDOW - 1e-9


def response(t: np.ndarray, T_r: np.ndarray, t_ref: np.ndarray, t_req: float, t_sync: float | None,
             noise: float | None = None) -> Response:
    """Figures of the response of ``T_r`` to the request ``t_ref`` made at ``t_req``; ``noise``: the standard
    deviation of the reading's white noise where the sensor's is known, else :func:`noise_std` estimates it."""
    t_end = t[-1] if t_sync is None else t_sync
    w0, w1 = t_req + STEADY_START, min(t_req + STEADY_END, t_end - 0.1)
    if not judged_window(w0, w1):
        # an early lock-up: the last MIN_WINDOW before it, if that starts once the response time allowed is over
        w0 = max(w1 - MIN_WINDOW, t_req + REQ_T95_S)
    waiting = standby(t, T_r, t_req)
    if not judged_window(w0, w1):
        return Response.empty(waiting, (w0, w1))
    win = (t >= w0) & (t <= w1)
    T_ss = float(np.mean(T_r[win]))
    ref = float(np.mean(t_ref[win]))
    if not ref > 0.0:  # no torque asked for over the window: no relative error, no 95 % level
        return Response.empty(waiting, (w0, w1))
    ess = abs(T_ss - ref) / ref * 100.0
    after = t >= t_req
    y = _smooth(t, T_r)
    asked = np.flatnonzero(after & (t_ref >= 0.95 * ref))
    t_start = float(t[asked[0]]) if asked.size else t_req
    reached = np.flatnonzero(after & (T_r >= 0.95 * T_ss))
    t95 = float(t[reached[0]] - t_start) if reached.size and T_ss > 0 else np.inf
    # the response phase ends where the steady window begins, counted from the start of the response's clock
    w_resp = min(t_start + STEADY_START, w1)
    # never before the first crossing: the centred average looks a few samples ahead of the reading
    settled = (max(_settled(t, T_r, after, T_ss, w_resp, w1, t_start, float(t[reached[0]])), t95)
               if T_ss > 0 and reached.size else np.inf)
    upto = after & (t <= w1)
    overshoot = max(0.0, (float(np.max(y[upto])) - T_ss) / T_ss * 100.0) if T_ss > 0 else np.nan
    # on the reading itself, not the smoothed one: a smoothing that hides the noise hides an oscillation
    # as fast (a 10 ms mean passes a tenth of 110 Hz); the noise's variance is taken out instead
    noise = noise_std(t, T_r, t_req) if noise is None else noise
    ripple = ripple_pct(T_r[win], noise) if T_ss > 0 else np.nan
    line = np.polyval(np.polyfit(t[win] - w0, T_r[win], 1), t[win] - w0)
    oscillation = _rms_less_noise(T_r[win] - line, noise) / T_ss * 100.0 if T_ss > 0 else np.nan
    slip = after & (t < t_end)
    rate = np.abs(np.diff(y)) / np.diff(t)
    jerk = float(np.max(rate[slip[1:]])) if np.any(slip[1:]) else np.nan
    return Response(T_ss, ess, t95, settled, overshoot, ripple, oscillation, jerk, *waiting, (w0, w1))


def requirements(r: Response, nominal: Response) -> dict[str, bool]:
    """Pass/fail of the requirements (:data:`REQUIREMENTS`)."""
    robust = (np.isfinite(nominal.t95_settled_s) and np.isfinite(r.t95_settled_s)
              and r.t95_settled_s - nominal.t95_settled_s <= ROBUST_DT95
              and r.overshoot_pct - nominal.overshoot_pct <= ROBUST_OVERSHOOT
              and r.ripple_pct <= REQ_RIPPLE_PCT)
    return {
        "steady_state_error": bool(r.steady_state_error_pct <= REQ_ESS_PCT),
        "response_time": bool(r.t95_settled_s < REQ_T95_S),
        "robustness": bool(robust),
        "standby": bool(r.creep_Nm <= REQ_CREEP_NM),
    }


def first_contact(t: np.ndarray, T_c: np.ndarray, t_req: float) -> float | None:
    """Time (s) from the request to the first sample with torque on the plates (``T_c``, the simulation's true
    clutch torque, exactly zero while they are open); negative when they touched before it, as a fill is
    meant to; None if they never did. Positive: the fill was not complete when torque was asked for, and the
    response time counts the rest of it."""
    touched = np.flatnonzero(T_c != 0.0)
    return float(t[touched[0]] - t_req) if touched.size else None


def input_at_max(t: np.ndarray, u: np.ndarray, u_max: float, window: tuple[float, float], T_r: np.ndarray,
                 t_ref: np.ndarray) -> float:
    """Share (%) of the samples of ``window`` with the input ``u`` at ``u_max``, the top of its range, and ``T_r``
    below the request ``t_ref`` (NaN: an empty window)."""
    win = (t >= window[0]) & (t <= window[1])
    short = (u[win] >= u_max) & (T_r[win] < t_ref[win])
    return float(np.mean(short) * 100.0) if np.any(win) else np.nan


def summary(r: Response, nominal: Response, slip_energy: float, t_sync: float | None,
            contact: float | None = None, input_max: float = np.nan) -> dict[str, Any]:
    """The ``summary.json`` figures of a launch; ``contact`` is the time (s) from the request to the plates' first
    contact (:func:`first_contact`), ``input_max`` the share of the steady window with the input at the top of its
    range and the torque short of the request (:func:`input_at_max`)."""
    req = requirements(r, nominal)
    d = asdict(r)
    d.pop("window")
    return {
        **{k: (None if not np.isfinite(v) else float(v)) for k, v in d.items()},
        "steady_window_s": list(r.window),
        "slip_energy_J": slip_energy,
        "t_sync_s": t_sync,
        "contact_s": contact,
        "input_at_max_pct": None if not np.isfinite(input_max) else input_max,
        "nominal_t95_settled_s": None if not np.isfinite(nominal.t95_settled_s) else nominal.t95_settled_s,
        "nominal_overshoot_pct": None if not np.isfinite(nominal.overshoot_pct) else nominal.overshoot_pct,
        "requirements": req,
        "all_pass": all(req.values()),
    }
