"""Validation of identified models on held-out files (leave one file out).

Each file is predicted by models identified from all the *other* files, so the
figures measure prediction, not fit:

* torque: ``T_r`` in the slip phase from the file's measured pressure, slip and
  ratio through the friction law with the ``mu(slip)`` polynomial fitted without it;
* pressure: a Hammerstein model, the static pressure-command curve of the other
  files of the same configuration and input mode followed by their median
  first-order-plus-dead-time dynamics (quasi-static if no other file had a step).

Figures: NRMSE (RMS error over the range of the measured signal) and VAF
(variance accounted for, %).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy import signal

from .estimate import source
from .result import Identification
from .static import GAIN_GROUPS, static_gain

#: the least VAF (%) of a step's first-order model that the pressure prediction takes: a step whose response is not
#: one of a first-order lag plus dead time (a fill, then the plates' contact) is fitted, shown, and not used
STEP_VAF_MIN = 50.0


def scores(measured: np.ndarray, predicted: np.ndarray) -> dict[str, float]:
    """NRMSE (RMS error / range of ``measured``) and VAF in % of a prediction."""
    e = measured - predicted
    span = float(np.ptp(measured))
    return {"nrmse": float(np.sqrt(np.mean(e**2)) / span) if span > 0 else float("nan"),
            "vaf_percent": float(100.0 * (1.0 - np.var(e) / np.var(measured))) if np.var(measured) > 0 else float("nan")}


def predict_pressure(t: np.ndarray, u: np.ndarray, gain: np.ndarray, p_range: tuple[float, float],
                     tau: float | None, theta: float | None) -> np.ndarray:
    """Hammerstein prediction: static curve ``gain`` (bar, polynomial in ``u``), then ``e^(-theta s) / (tau s + 1)``.

    The curve is held within ``p_range`` (bar), the static pressures seen: outside
    them a polynomial extrapolates freely, the valve does not.
    """
    x = np.clip(np.polyval(gain, u), *p_range) * 1e5
    if tau is None or theta is None:
        return x
    dt = float(t[1] - t[0])
    x = np.interp(t - theta, t, x)
    a = float(np.exp(-dt / max(tau, 1e-9)))
    # start in steady state: the rig held its first command long before recording
    y, _ = signal.lfilter([1.0 - a], [1.0, -a], x, zi=[a * x[0]])
    return y


def validate(result: Identification) -> list[dict[str, Any]]:
    """Leave-one-file-out validation of torque and pressure models (see the module docstring)."""
    out: list[dict[str, Any]] = []
    if "mu_slip_poly" in result.estimates and len(result.slips) > 1:
        order = len(result.estimates["mu_slip_poly"].value) - 1
        # normal equations per file: leaving one out is a subtraction, not a refit over all the others
        grams = [(X.T @ X, X.T @ s.mu) for s in result.slips for X in [np.vander(s.slip, order + 1)]]
        gram_all, rhs_all = sum(g for g, _ in grams), sum(r for _, r in grams)
        for s, (g, r) in zip(result.slips, grams):
            try:
                coef = np.linalg.solve(gram_all - g, rhs_all - r)
            except np.linalg.LinAlgError:  # the other files cannot determine the polynomial
                continue
            pred = s.factor * np.polyval(coef, s.slip) + s.offset
            out.append({"file": str(s.rec.path), "signal": "T_r", "window": source(s.rec, s.t0, s.t1),
                        "model": "friction law, mu(slip) from the other files", **scores(s.T_r, pred),
                        "trace": {"slip": s.slip, "measured": s.T_r, "predicted": pred}})
    orders = {(c, m): k for c, m, k in GAIN_GROUPS.values()}
    for rec in result.recordings:
        key = (rec.config, rec.input_mode)
        points = [q for q in result.plateaus if q.rec is not rec and (q.rec.config, q.rec.input_mode) == key]
        curve = static_gain(points, orders[key])
        if curve is None:
            continue
        models = [m for m in result.steps if m.rec is not rec and m.order == 1
                  and (m.rec.config, m.rec.input_mode) == key and m.vaf > STEP_VAF_MIN]
        tau = float(np.median([m.params["tau_s"] for m in models])) if models else None
        theta = float(np.median([m.theta for m in models])) if models else None
        pred = predict_pressure(rec.t, rec.data["u"], np.array(curve.value), curve.extra["range_bar"], tau, theta)
        out.append({"file": str(rec.path), "signal": "p_clutch", "window": source(rec, rec.t[0], rec.t[-1]),
                    "model": ("static curve + first order plus dead time" if models else "static curve")
                    + " from the other files", **scores(rec.data["p_clutch"], pred),
                    "trace": {"time": rec.t, "measured": rec.data["p_clutch"], "predicted": pred}})
    return out
