"""Friction versus slip from the slip phase of clutch runs: the ``mu(slip)`` polynomial."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import maximum_filter1d

from ..errors import ParameterError, WetclutchError
from ..params import Driveline, Params
from ..physics import friction as law
from .estimate import BAR, Estimate, aligned, inflation, robust_std, smooth, source
from .onset import Onset
from .recordings import Recording

SLIP_MIN = 10.0  # rad/s: below it the speed sensors' resolution spoils the slip
W_RATIO = 20.0  # rad/s: CVT input speed above which the speeds give the ratio


@dataclass
class SlipSamples:
    """Friction samples of the slip phase of one clutch run."""

    rec: Recording
    slip: np.ndarray  # rad/s
    mu: np.ndarray  # m
    p: np.ndarray  # Pa
    T_r: np.ndarray  # N m, measured
    factor: np.ndarray  # T_r per unit mu: eta / i * F_n * knee(F_n)
    offset: np.ndarray  # T_r of the oil drag, N m
    ratio: float
    t0: float
    t1: float


def measured_ratio(rec: Recording) -> tuple[float, float]:
    """CVT ratio ``omega_r / omega_1`` (median where ``omega_1`` exceeds :data:`W_RATIO`) and its standard error.

    Both nan where fewer than 20 samples qualify: then the speeds cannot give the ratio.
    """
    w1, wr = rec.data["omega_1"], rec.data["omega_r"]
    ok = w1 > W_RATIO
    if np.count_nonzero(ok) < 20:
        return float("nan"), float("nan")
    r = wr[ok] / w1[ok]
    m = float(np.median(r))
    return m, float(1.2533 * np.std(r) / np.sqrt(r.size) * np.sqrt(inflation(r - m)))


def commanded_ratio(rec: Recording) -> float | None:
    """The CVT ratio the rig was set to, if the recording's ``meta.json`` says it (``params.driveline.ratio``,
    within the parameter's range)."""
    given = rec.meta.get("params")
    driveline = given.get("driveline") if isinstance(given, dict) else None
    if not isinstance(driveline, dict) or "ratio" not in driveline:
        return None
    try:
        return Driveline(ratio=driveline["ratio"]).ratio
    except ParameterError:
        return None


def slip_samples(rec: Recording, prior: Params, p_contact: float, on: Onset | None,
                 ratio: float) -> SlipSamples | None:
    """Friction coefficient samples ``mu = T_c / (F_n knee(F_n))`` of the slip phase.

    ``T_c = T_r i / eta - d_drag slip`` with ``i = ratio`` the run's CVT ratio, ``eta`` the
    prior efficiency (forward power flow: before synchronisation) and ``d_drag``
    the oil drag seen before the onset; ``F_n = (p - p_contact) A_p`` with the
    prior piston area. The model's friction drops at low normal force by the
    knee ``F_n / (F_n + F_knee)``; it is divided out with the prior ``F_knee``,
    and only samples with ``F_n > F_knee`` (knee factor above 1/2) are kept, so
    that an error in ``F_knee`` moves ``mu`` little. Also left out: slip below
    :data:`SLIP_MIN`, small or negative torque, and transients (fast changes of
    pressure or of the CVT input speed, which the sensors' filters smear).
    """
    if rec.config != "clutch":
        return None
    d = aligned(rec)
    t, p, T = rec.t, d["p_clutch"], d["T_r"]
    dr, h, fr = prior.driveline, prior.hydraulics, prior.friction
    slip = d["omega_p"] - d["omega_1"]
    n = max(1, int(round(0.01 / rec.dt)))
    dp = np.abs(np.gradient(smooth(p, n), t))
    dw = np.abs(np.gradient(smooth(d["omega_1"], n), t))
    # 50 ms either side of a transient is spoiled too
    span = 2 * int(round(0.05 / rec.dt)) + 1
    calm = (maximum_filter1d(dp, span) < 20.0 * BAR) & (maximum_filter1d(dw, span) < 500.0)
    f_n = law.normal_force.py_func(p, p_contact, h.A_p)
    noise = on.noise if on is not None else robust_std(np.diff(T)) / np.sqrt(2.0)
    ok = calm & (slip > SLIP_MIN) & (f_n > max(fr.F_knee, 1.0)) & (T > max(10.0 * noise, 0.05 * np.max(T)))
    if on is not None:
        ok &= t > on.t_command + on.dead_time
    if np.count_nonzero(ok) < 20:
        return None
    drag = on.baseline * ratio / dr.eta / on.slip0 if on is not None and on.slip0 > SLIP_MIN else 0.0
    knee = law.knee.py_func(f_n[ok], fr.F_knee)
    factor = dr.eta / ratio * f_n[ok] * knee
    offset = dr.eta / ratio * drag * slip[ok]
    mu = (T[ok] - offset) / factor
    return SlipSamples(rec, slip[ok], mu, p[ok], T[ok], factor, offset, ratio, float(t[ok][0]), float(t[ok][-1]))


def fit_mu(samples: Sequence[SlipSamples], order: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Least-squares ``mu(slip)`` polynomial (highest power first), its covariance and the residual RMS."""
    slip = np.concatenate([s.slip for s in samples])
    mu = np.concatenate([s.mu for s in samples])
    if slip.size <= order + 1:
        raise WetclutchError(f"too few slip samples ({slip.size}) for a mu polynomial of order {order}")
    X = np.vander(slip, order + 1)
    coef, *_ = np.linalg.lstsq(X, mu, rcond=None)
    resid = mu - X @ coef
    # residuals are correlated in time within each file (filtered sensors): inflate per file
    infl = float(np.mean(np.concatenate([np.full(s.slip.size, inflation(s.mu - np.vander(s.slip, order + 1) @ coef))
                                         for s in samples])))
    s2 = float(resid @ resid) / (slip.size - order - 1)
    cov = s2 * infl * np.linalg.pinv(X.T @ X)
    return coef, cov, float(np.sqrt(np.mean(resid**2)))


def friction(samples: Sequence[SlipSamples], order: int = 2) -> Estimate:
    """``mu(slip)`` polynomial with standard errors, plus ``mu`` binned by pressure and by oil temperature."""
    coef, cov, rms = fit_mu(samples, order)
    p = np.concatenate([s.p for s in samples])
    mu = np.concatenate([s.mu for s in samples])
    edges = np.arange(np.floor(p.min() / (0.5 * BAR)), np.ceil(p.max() / (0.5 * BAR)) + 1) * 0.5 * BAR
    which = np.digitize(p, edges) - 1
    by_p = [{"p_bar": [float(edges[k] / BAR), float(edges[k + 1] / BAR)], "mu": float(mu[which == k].mean()),
             "se": float(mu[which == k].std() / np.sqrt(np.count_nonzero(which == k))), "n": int(np.count_nonzero(which == k))}
            for k in range(edges.size - 1) if np.count_nonzero(which == k) >= 20]
    temps = np.concatenate([np.full(s.mu.size, 5.0 * round(s.rec.oil_temp_C / 5.0)) for s in samples])
    by_t = [{"oil_temp_C": float(T), "mu": float(mu[temps == T].mean()),
             "se": float(mu[temps == T].std() / np.sqrt(np.count_nonzero(temps == T))), "n": int(np.count_nonzero(temps == T))}
            for T in np.unique(temps)]
    return Estimate(
        [float(c) for c in coef], [float(s) for s in np.sqrt(np.diag(cov))], "m (slip in rad/s, highest power first)",
        [source(s.rec, s.t0, s.t1) for s in samples],
        {"order": order, "residual_rms": rms, "n_samples": int(mu.size),
         "slip_range": [float(min(s.slip.min() for s in samples)), float(max(s.slip.max() for s in samples))],
         "covariance": cov.tolist(), "by_pressure": by_p, "by_temperature": by_t},
    )
