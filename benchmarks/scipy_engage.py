"""Baseline driveline engagement with :func:`scipy.integrate.solve_ivp`.

A typical hand-written implementation used as a speed baseline for the
compiled engine: a Python right-hand side, terminal ``events`` for the mode
switches and a loop that restarts ``solve_ivp`` after every event.

Bodies: primary ``p`` (speed ``w_p``), clutch-output / CVT-input body ``1``
(speed ``w_1``, small inertia ``J_1``), massless CVT output ``r`` with
``w_r = i*w_1``, a flexible axle from ``r`` to the secondary ``s`` (twist
``phi``) and the secondary ``s`` (speed ``w_s``) braked by the road load.
State vector: ``y = [w_p, w_1, phi, w_s]``.
"""
import time

import numpy as np
from scipy.integrate import solve_ivp

OPEN, LOCKED = 0, 2  # clutch modes; +1 / -1 mean slipping with sign(w_p - w_1)
HELD = 0  # road mode; +1 / -1 mean rolling in that direction

DEFAULTS = dict(J_p=1.2, J_1=1e-3, J_s=6.5, b_1=2e-5, b_2=5e-5, i=0.5, eta=0.95,
                k_a=480.0, d_a=5.0, omega_p0=150.0, T_cap=40.0, t_start=0.5,
                t_ramp=0.3, T_load=10.0, peak=1.0)


def _cap(p, t):
    """Clutch capacity ``T_cap(t)``: linear ramp from ``t_start`` over ``t_ramp``."""
    return p["T_cap"] * min(max((t - p["t_start"]) / p["t_ramp"], 0.0), 1.0)


def _axle(p, y):
    """Return the axle torque ``T_r`` and the torque acting on body 1 from the CVT."""
    w_r = p["i"] * y[1]
    T_r = p["k_a"] * y[2] + p["d_a"] * (w_r - y[3])
    c = 1.0 / p["eta"] if T_r * w_r >= 0.0 else p["eta"]
    return T_r, p["i"] * c * T_r


def _locked_torque(p, y):
    """Clutch torque needed to keep ``w_1 == w_p == y[0]``."""
    _, T_cvt = _axle(p, y)
    dw = (-p["b_1"] * y[0] * abs(y[0]) - T_cvt) / (p["J_p"] + p["J_1"])
    return p["J_1"] * dw + T_cvt


def _rhs(t, y, p, clutch, road):
    """Time derivative of ``y`` for the given clutch and road modes."""
    w_p, w_1, _, w_s = y
    T_r, T_cvt = _axle(p, y)
    drag_p = p["b_1"] * w_p * abs(w_p)
    if clutch == LOCKED:
        dw_p = dw_1 = (-drag_p - T_cvt) / (p["J_p"] + p["J_1"])
    else:
        T_c = clutch * _cap(p, t)  # zero when open
        dw_p = (-drag_p - T_c) / p["J_p"]
        dw_1 = (T_c - T_cvt) / p["J_1"]
    if road == HELD:
        dw_s = 0.0
    else:
        dw_s = (T_r - p["b_2"] * w_s * abs(w_s) - p["T_load"] * road) / p["J_s"]
    return [dw_p, dw_1, p["i"] * w_1 - w_s, dw_s]


def _event(fun, direction):
    """Mark ``fun(t, y, *args)`` as a terminal event crossing zero in ``direction``."""
    fun.terminal, fun.direction = True, direction
    return fun


def _events(p, clutch, road):
    """Terminal events of the current modes as a list of ``(name, function)``."""
    events = []
    if clutch == LOCKED:
        events.append(("unlock", _event(
            lambda t, y, *_: abs(_locked_torque(p, y)) - p["peak"] * _cap(p, t), 1)))
    elif clutch != OPEN:
        events.append(("lock", _event(lambda t, y, *_: y[0] - y[1], -clutch)))
    if road == HELD:
        events.append(("release", _event(lambda t, y, *_: abs(_axle(p, y)[0]) - p["T_load"], 1)))
    else:
        events.append(("stop", _event(lambda t, y, *_: y[3], -road)))
    return events


def engage_scipy(p: dict, t_end: float = 8.0, rtol: float = 1e-8, atol: float = 1e-10,
                 method: str = "RK45") -> dict:
    """Simulate a clutch engagement from 0 to ``t_end`` with ``solve_ivp``.

    Parameters
    ----------
    p : dict
        Driveline parameters in SI units (see ``DEFAULTS`` for the keys).
    t_end : float
        End time (s).
    rtol, atol : float
        Tolerances passed to ``solve_ivp``.
    method : str
        ``solve_ivp`` integration method.

    Returns
    -------
    dict
        ``t_sync`` (first lock time or None), ``omega_p_end``, ``omega_s_end``,
        ``n_events`` (event-triggered mode switches) and the concatenated
        segment outputs ``t`` (n,) and ``y`` (4, n); restart points appear twice.
    """
    p = {"peak": 1.0, **p}
    t_ramp_end = p["t_start"] + p["t_ramp"]
    bounds = sorted({b for b in (p["t_start"], t_ramp_end) if 0.0 < b < t_end} | {t_end})
    t0, y0 = 0.0, np.array([p["omega_p0"], 0.0, 0.0, 0.0])
    clutch, road = OPEN, HELD
    t_sync, n_events, stalls = None, 0, 0
    ts, ys = [], []
    for t_b in bounds:
        if clutch == OPEN and t0 >= p["t_start"]:
            clutch = 1 if y0[0] >= y0[1] else -1
        while t0 < t_b:
            named = _events(p, clutch, road)
            sol = solve_ivp(_rhs, (t0, t_b), y0, method=method, rtol=rtol, atol=atol,
                            args=(p, clutch, road), events=[f for _, f in named])
            ts.append(sol.t)
            ys.append(sol.y)
            stalls = stalls + 1 if sol.t[-1] <= t0 else 0
            if stalls > 10:
                raise RuntimeError(f"event loop stalled at t={t0}")
            t0, y0 = sol.t[-1], sol.y[:, -1].copy()
            if sol.status != 1:
                break
            n_events += 1
            name = next(n for (n, _), te in zip(named, sol.t_events) if te.size)
            if name == "lock":
                y_lock = y0.copy()
                y_lock[1] = y_lock[0]
                if abs(_locked_torque(p, y_lock)) <= p["peak"] * _cap(p, t0):
                    clutch, y0 = LOCKED, y_lock
                    t_sync = float(t0) if t_sync is None else t_sync
                else:
                    clutch = -clutch
            elif name == "unlock":
                clutch = 1 if _locked_torque(p, y0) > 0.0 else -1
            elif name == "release":
                road = 1 if _axle(p, y0)[0] > 0.0 else -1
            else:  # stop: w_s reached zero while rolling
                y0[3] = 0.0
                T_r = _axle(p, y0)[0]
                road = HELD if abs(T_r) <= p["T_load"] else (1 if T_r > 0.0 else -1)
    return {"t_sync": t_sync, "omega_p_end": float(y0[0]), "omega_s_end": float(y0[3]),
            "n_events": n_events, "t": np.concatenate(ts), "y": np.concatenate(ys, axis=1)}


if __name__ == "__main__":
    n_runs = 5
    start = time.perf_counter()
    for _ in range(n_runs):
        res = engage_scipy(DEFAULTS)
    wall = (time.perf_counter() - start) / n_runs
    print(f"RK45 rtol=1e-8: t_sync={res['t_sync']!r} s, omega_p_end={res['omega_p_end']:.6f}, "
          f"omega_s_end={res['omega_s_end']:.6f}, n_events={res['n_events']}, "
          f"points={res['t'].size}, wall={wall * 1e3:.1f} ms/run")
    for method in ("DOP853", "LSODA"):
        ref = engage_scipy(DEFAULTS, rtol=1e-12, atol=1e-13, method=method)
        rel = abs(ref["t_sync"] - res["t_sync"]) / ref["t_sync"]
        print(f"{method} rtol=1e-12: t_sync={ref['t_sync']!r} s, rel. diff vs RK45 {rel:.2e}")
    T_r = np.array([_axle(DEFAULTS, y)[0] for y in res["y"].T])
    after = res["t"] > res["t_sync"]
    peaks = res["t"][after][1:-1][np.diff(np.sign(np.diff(T_r[after]))) < 0]
    print(f"axle ringing after sync: {1.0 / np.mean(np.diff(peaks[:6])):.3f} Hz")
