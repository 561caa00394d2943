"""Torque hold after lock-up: the CVT ratio moves so that the axle torque stays at the request.

Once the clutch has locked, both its sides turn together and it passes no more torque of
its own accord: the primary flywheel and the vehicle are then one rigid system through
the CVT, and the axle torque rings down to what the road load takes. Moving the ratio
``i = w_r / w_1`` makes the CVT output turn faster than the vehicle, winding up the axle:
the kinetic energy of the primary flows on into the vehicle at the requested torque
until a stated limit: the ratio's greatest value, the hold's time limit (from its start), or
the CVT's rate limit no longer keeping up (the torque more than :data:`BAND` low at the full
rate; the ratio then goes on at its rate limit to a limit, so that the axle unwinds gently).

Physics of the hold. With the clutch locked, ``J_a w_p' = -i T_r / eta`` (``J_a`` the
primary side's inertia, power flowing forward) and the axle winds up at ``T_r' ~ k_a v``,
``v = i w_p - w_s`` the speed across it. Holding ``T_r`` asks for ``v' = 0``::

    i' w_p = i^2 T_r / (eta J_a) + a_s,      a_s = w_s' = (T_r - T_load) / J_s

The controller gives ``u = i' w_p`` as that feedforward (with ``a_s`` as the secondary
flywheel accelerated just before the hold, when the axle torque was at the request) plus
a PID-like feedback ``K_T e - K_v v + K_I int(e)`` on the torque error ``e = T_ref - T_r``
and the speed across the axle as the locked driveline has it, ``v = i w_p - w_s`` from the
measured speeds. The hold starts in the clutch's last slip (:data:`HOLD_SLIP`): ``v`` then
counts that slip, and the ratio falling to ``w_s / w_p`` closes it, so that the lock does not
make ``w_1`` jump and wind up the axle (the launch controller's closing of the clutch waits
for it: :func:`valve`). With ``e' = -k_a v`` the loop's characteristic
polynomial is ``s^3 + K_v s^2 + k_a K_T s + k_a K_I``, placed at a triple pole
:data:`POLE`. The ratio rate ``u / w_p`` is held within the CVT's rate limit and its
ratio within its limits (the controller integrates its own command, which the CVT
follows); the integrator stops while the rate is saturated.

Why the hold ends. The primary's kinetic energy ``J_a w_p^2 / 2`` at lock-up is all that
can feed the axle: the hold takes ``T_ref w_s / eta`` from it. As ``w_p`` falls the ratio
rate needed, ``i^2 T_ref / (eta J_a w_p)``, grows without bound: the rate limit (and in the
end the ratio limit) is met before the energy is gone, and the torque then falls away. A
small request locks late (a long slip phase, at a lower primary speed) but draws little
power; a large one locks early with more energy left but draws it fast. On the default
rig (noise seed 0) requests of 20 to 35 N m keep the axle torque within 10 % for 1.8 to 1.1 s
after lock-up (20 N m locks 13 s into the run), 40 N m for 0.96 s and 60 N m for 0.58 s; at
100 N m the hold lasts 0.35 s but the lock-up's jolt leaves the band. 15 N m locks only at
18.6 s, with the primary nearly spent (no time within the band), and at 10 N m the primary runs
down to rest before the clutch locks: nothing is left to hold.

The record (:func:`pack`) and the state vector are flat float arrays; this module names
their slots and alone packs the record.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit

from ..params import Params
from ..errors import WetclutchError
from .controller import M_TR, M_W1, M_WP, M_WS

_jit = njit(cache=True, error_model="numpy", _nrt=False)

#: triple pole of the torque loop, rad/s: some five times the locked driveline's 2.1 Hz ringing
#: would need a faster ratio than a CVT has; 10 rad/s settles the lock-up's jolt in some 0.3 s
POLE = 10.0
#: secondary's acceleration estimate: low-pass time constants of the speed and of its derivative, s (the speed's
#: sensor noise, differentiated at the sample rate, would swamp it otherwise)
TAU_W, TAU_ACC = 0.05, 0.1
#: below this primary speed (rad/s) the hold stops: the ratio rate it needs has no bound
W_MIN = 1.0
#: measured clutch slip (rad/s) below which the hold starts, once torque is requested: the clutch's last slip is
#: closed by the ratio too (the ratio falls to w_s / w_p), so that no jump of w_1 at lock winds up the axle
HOLD_SLIP = 4.0
#: the hold ends once the ratio has run at its rate limit for this many samples with the axle torque more than
#: BAND below the request: the flywheel has slowed past what the CVT can follow
SAT_N = 20
BAND = 0.1
#: measured slip (rad/s) below which the clutch counts as locked in the hold, and the longest the valve waits for it, s
LOCK_SLIP, LOCK_WAIT = 0.25, 0.2
#: time limit of the hold by default, s
HOLD_TIME = 3.0

# --- record
DT, J_A, ETA, K_A, R_MIN, R_MAX, RATE, T_LIMIT, KV, KT, KI = range(11)
N_REC = 11
# --- state
(HS_ON, HS_DONE, HS_T, HS_RATIO, HS_Z, HS_ACC, HS_WS, HS_N, HS_REASON, HS_START, HS_SAT, HS_K, HS_SHUT) = range(13)
#: the launch controller's last N_RING valve inputs (a ring), replayed while its lock-up waits
HS_RING, N_RING = 13, 8
N_HS = HS_RING + N_RING
#: why the hold ended (HS_REASON)
RUNNING, RATIO_LIMIT, TIME_LIMIT, NO_SPEED, RATE_LIMIT = range(5)
REASONS = ("running", "ratio limit", "time limit", "primary at rest", "rate limit")


def pack(params: Params, dt: float, t_limit: float = HOLD_TIME) -> np.ndarray:
    """The hold's record for sample time ``dt`` (s) and time limit ``t_limit`` (s) on the plant ``params``.

    Raises
    ------
    WetclutchError
        If the CVT's ratio lies outside its limits.
    """
    d = params.driveline
    if not d.ratio_min <= d.ratio <= d.ratio_max:
        raise WetclutchError(f"driveline.ratio {d.ratio:g} must lie within driveline.ratio_min {d.ratio_min:g} .. "
                             f"driveline.ratio_max {d.ratio_max:g} for the post-sync hold")
    r = np.zeros(N_REC)
    r[DT], r[J_A], r[ETA], r[K_A] = dt, d.J_p + d.J_1, d.eta, d.k_a
    r[R_MIN], r[R_MAX], r[RATE], r[T_LIMIT] = d.ratio_min, d.ratio_max, d.ratio_rate, t_limit
    r[KV], r[KT], r[KI] = 3.0 * POLE, 3.0 * POLE**2 / d.k_a, POLE**3 / d.k_a
    return r


def initial_state(params: Params) -> np.ndarray:
    """The hold's state before a launch: off, at the CVT's ratio."""
    hs = np.zeros(N_HS)
    hs[HS_RATIO] = params.driveline.ratio
    return hs


@_jit
def step(rec, hs, meas, t_ref, engaged):
    """One sample: the commanded ratio rate (1/s) from the measured channels ``meas``, the request ``t_ref``
    (N m) and whether the launch controller is past its fill and hold (``engaged``)."""
    dt = rec[DT]
    # the secondary's acceleration, low-passed: before the hold the axle carries the request
    if hs[HS_N] == 0.0:
        hs[HS_WS] = meas[M_WS]
    w_s = hs[HS_WS] + (meas[M_WS] - hs[HS_WS]) * dt / (TAU_W + dt)
    hs[HS_ACC] += ((w_s - hs[HS_WS]) / dt - hs[HS_ACC]) * dt / (TAU_ACC + dt)
    hs[HS_WS] = w_s
    hs[HS_N] += 1.0
    if hs[HS_DONE] != 0.0 or not (engaged and t_ref > 0.0):
        return 0.0
    if hs[HS_ON] == 0.0:
        if not (abs(meas[M_WP] - meas[M_W1]) < HOLD_SLIP and meas[M_W1] > 0.0):
            return 0.0
        hs[HS_ON] = 1.0
        hs[HS_Z] = hs[HS_ACC]
        hs[HS_START] = (hs[HS_N] - 1.0) * dt
    i = hs[HS_RATIO]
    w_p = meas[M_WP]
    stop = RUNNING
    if (hs[HS_N] - 1.0) * dt - hs[HS_START] >= rec[T_LIMIT]:
        stop = TIME_LIMIT
    elif i >= rec[R_MAX]:
        stop = RATIO_LIMIT
    elif w_p < W_MIN:
        stop = NO_SPEED
    if stop != RUNNING:
        hs[HS_DONE] = 1.0
        if hs[HS_REASON] == RUNNING:
            hs[HS_REASON] = stop
        return 0.0
    hi = min(rec[RATE], (rec[R_MAX] - i) / dt)
    if hs[HS_SAT] >= SAT_N:
        # the hold is over (it ended when the rate limit was first met with the torque low); the ratio goes on at
        # its rate limit (to its limit or the time limit), so that the axle unwinds gently: a ratio stopped here
        # would let the slowing flywheel reverse the axle torque
        if hs[HS_REASON] == RUNNING:
            hs[HS_T] -= SAT_N * dt
        hs[HS_REASON] = RATE_LIMIT
        hs[HS_RATIO] = min(i + hi * dt, rec[R_MAX])
        return hi
    hs[HS_T] += dt
    e = t_ref - meas[M_TR]
    # the speed across the axle as the locked driveline has it (w_r = i w_p): before the lock it already counts
    # the clutch's last slip, which the ratio then closes
    v = i * w_p - meas[M_WS]
    u = i * i * t_ref / (rec[ETA] * rec[J_A]) + hs[HS_Z] + rec[KT] * e - rec[KV] * v
    rate = u / w_p
    lo = max(-rec[RATE], (rec[R_MIN] - i) / dt)
    hs[HS_SAT] = hs[HS_SAT] + 1.0 if (rate > rec[RATE] and e > BAND * t_ref) else 0.0
    if rate > hi:
        rate = hi
        if e < 0.0:
            hs[HS_Z] += rec[KI] * e * dt
    elif rate < lo:
        rate = lo
        if e > 0.0:
            hs[HS_Z] += rec[KI] * e * dt
    else:
        hs[HS_Z] += rec[KI] * e * dt
    hs[HS_RATIO] = min(max(i + rate * dt, rec[R_MIN]), rec[R_MAX])
    return rate


@_jit
def valve(hs, meas, u, lockup):
    """The valve input ``u`` of the launch controller, with the hold: its lock-up (``lockup``: the input that
    closes the clutch firmly) waits until the ratio has closed the last slip.

    While the clutch slips the axle torque follows the clutch torque (the CVT input is light); closing the
    clutch on a slip left would jolt the axle. Until the measured slip is below :data:`LOCK_SLIP` (or for at most
    :data:`LOCK_WAIT`) the torque loop's last inputs are replayed: their mean and the dither on it, which keeps
    the valve stem from sticking (a steady input lets the pressure sag)."""
    k = int(hs[HS_K])
    hs[HS_K] = k + 1
    if not lockup:
        hs[HS_RING + k % N_RING] = u
        return u
    if hs[HS_SHUT] == 0.0 and hs[HS_ON] != 0.0 and hs[HS_T] < LOCK_WAIT and abs(meas[M_WP] - meas[M_W1]) >= LOCK_SLIP:
        return hs[HS_RING + k % N_RING]
    hs[HS_SHUT] = 1.0
    return u


def summary(t: np.ndarray, T_r: np.ndarray, t_ref: np.ndarray, ratio: np.ndarray, t_sync: float | None,
            hs: np.ndarray, band: float = BAND) -> dict[str, Any]:
    """Figures of the hold from the true axle torque ``T_r`` (N m), the request and the CVT's ratio on times ``t``.

    ``hold_s`` is how long the controller held (from ``hold_start_s``, until its limit, ``hold_end``);
    ``held_in_band_s`` how long after lock-up (``t_sync``) the axle torque stayed within ``band`` of the
    request without a break; the errors are over the hold, relative to the request.
    """
    out: dict[str, Any] = {"post_sync_hold": True, "hold_s": float(hs[HS_T]),
                           "hold_start_s": float(hs[HS_START]) if hs[HS_ON] else None,
                           "hold_end": REASONS[int(hs[HS_REASON])] if hs[HS_ON] else "not started",
                           "ratio_start": float(ratio[0]), "ratio_end": float(ratio[-1]),
                           "ratio_min_run": float(np.min(ratio)), "ratio_max_run": float(np.max(ratio)),
                           "held_in_band_s": 0.0, "hold_T_r_err_max_pct": None, "hold_T_r_err_rms_pct": None}
    if t_sync is None or hs[HS_T] <= 0.0:
        return out
    after = t >= t_sync
    ref = np.where(t_ref > 0.0, t_ref, np.nan)
    rel = np.abs(T_r - ref) / ref
    outside = np.flatnonzero(after & ~(rel <= band))
    t_out = t[outside[0]] if outside.size else t[-1]
    out["held_in_band_s"] = float(t_out - t_sync)
    during = (t >= hs[HS_START]) & (t <= hs[HS_START] + hs[HS_T])
    if np.any(during):
        out["hold_T_r_err_max_pct"] = float(100.0 * np.nanmax(rel[during]))
        out["hold_T_r_err_rms_pct"] = float(100.0 * np.sqrt(np.nanmean(rel[during] ** 2)))
    return out
