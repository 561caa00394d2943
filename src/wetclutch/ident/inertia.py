"""Driveline inertias from the torque and speed balances of clutch runs.

The measured axle torque ``T_r`` and the speeds give two balances that hold in
every phase of a run, slipping or locked, without the clutch torque:

* secondary flywheel: ``J_s dw_s/dt = T_r - T_b - b_2 w_s |w_s|``, with the
  brake's torque ``T_b`` constant while the flywheel turns (a Coulomb brake);
* primary side: ``J_p dw_p/dt + J_1 dw_1/dt = -c i T_r - b_1 w_p |w_p|``, the
  CVT's input torque with ``c = 1/eta`` while power flows forward
  (``T_r w_r > 0``) and ``c = eta`` back.

Both are linear in the inertias. Integrated over short intervals they say that
each speed's change times its inertia equals the torque's integral: least
squares over the intervals of a run. In the slip phase ``w_p`` and ``w_1`` move
apart and separate ``J_p`` from ``J_1``; locked, only their sum shows. The drag
coefficients and ``eta`` are the prior's, the ratio the run's. An inertia counts
as identified when its standard error is below :data:`REL_SE_MAX` of its value;
else the data do not excite it. The ring-out frequency then gives the axle
stiffness with these inertias (:func:`wetclutch.ident.result.identified_values`).

Before the balances are formed, each channel is passed through the other
channels' (distinct) sensor filters (:data:`wetclutch.rig.sensors.DEFAULT_SENSORS`)
and a common low-pass, so that torque and speeds carry the same filtering.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import signal
from scipy.ndimage import binary_dilation

from ..params import Params
from ..rig.sensors import DEFAULT_SENSORS
from .estimate import inflation
from .recordings import Recording

REL_SE_MAX = 0.1  # largest standard error, relative to the value, of an identified inertia
W_MIN = 2.0  # rad/s: speed sensors read 0 below about 1 rad/s; the balances use faster samples only
INTERVAL = 0.05  # s: the balances are integrated over intervals this long
SMOOTH_HZ = 20.0  # Hz: a low-pass common to all channels against the speeds' noise (ring-out and slip are slower)
SPEEDS = ("omega_p", "omega_1", "omega_s")
J_P_HELD = "J_p with J_1 held"  # key of InertiaFit.values: J_p fitted with J_1 at the prior's


@dataclass(frozen=True)
class InertiaFit:
    """Least-squares inertias of one clutch run.

    ``values`` maps ``J_p``, ``J_1`` (fitted together), :data:`J_P_HELD` and ``J_s``
    (those the run has samples for) to ``(value, standard error)`` in kg m^2.
    """

    rec: Recording
    values: dict[str, tuple[float, float]]
    t0: float
    t1: float


@lru_cache(maxsize=16)
def _lowpass(cutoffs_hz: tuple[float, ...], fs: float) -> np.ndarray:
    """Second-order Butterworth low-passes in series, as second-order sections."""
    return np.vstack([signal.butter(2, fc, fs=fs, output="sos") for fc in cutoffs_hz])


def _same_filtering(rec: Recording, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """``names``' channels, each passed through the sensor filters of the others that it has not had (the
    distinct cut-offs but its own) and through :data:`SMOOTH_HZ`: all then carry one common filtering."""
    fs = 1.0 / rec.dt
    cutoff = {c: DEFAULT_SENSORS[c].cutoff_hz if c in DEFAULT_SENSORS else None for c in names}
    distinct = {fc for fc in (*cutoff.values(), SMOOTH_HZ) if fc is not None and fc < 0.5 * fs}
    out = {}
    for own in set(cutoff.values()):
        group = [c for c in names if cutoff[c] == own]
        x = np.array([rec.data[c] for c in group])
        if not distinct - {own}:  # sampled too slowly for any of the filters
            out |= dict(zip(group, x))
            continue
        sos = _lowpass(tuple(sorted(distinct - {own})), fs)
        # start in steady state: the rig's filters had run long before the recording
        y, _ = signal.sosfilt(sos, x, zi=signal.sosfilt_zi(sos)[:, None, :] * x[None, :, :1])
        out |= dict(zip(group, y))
    return out


def _lstsq(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares coefficients and their standard errors, widened for correlated residuals."""
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    resid = y - X @ coef
    s2 = float(resid @ resid) / max(y.size - X.shape[1], 1)
    return coef, np.sqrt(np.abs(np.diag(s2 * inflation(resid) * np.linalg.pinv(X.T @ X))))


def inertias(rec: Recording, prior: Params, ratio: float) -> InertiaFit | None:
    """The inertias of one clutch run from the two balances (see the module docstring).

    ``ratio`` is the CVT ratio ``w_r / w_1`` of the run (measured, or the prior's
    where the speeds cannot give it). The balances are integrated over
    consecutive intervals of :data:`INTERVAL`: the change of each speed against
    the torque's integral, exact however the torque varies within an interval
    (a smoothed derivative would weigh the two sides differently). Intervals
    are used where every speed of a balance exceeds :data:`W_MIN`, a filter
    length away from where one does not.
    """
    if rec.config != "clutch":
        return None
    names = ("T_r", *(w for w in SPEEDS if w in rec.data))
    d = _same_filtering(rec, names)
    n = max(2, int(round(INTERVAL / rec.dt)))
    if rec.t.size < 8 * n:
        return None
    dr = prior.driveline
    T, w_p = d["T_r"], d["omega_p"]
    c = np.where(T * d["omega_1"] > 0.0, 1.0 / dr.eta, dr.eta)
    # torque integrals from the start, and their change over each interval [k, k + n]
    integral = lambda x: np.concatenate([[0.0], np.cumsum(0.5 * (x[1:] + x[:-1]) * np.diff(rec.t))])  # noqa: E731
    over = lambda x: x[n::n] - x[:-n:n]  # noqa: E731
    edge = np.zeros(rec.t.size, dtype=bool)
    edge[:n] = edge[-n:] = True  # the cross filters start up

    def usable(*speeds: str) -> np.ndarray:
        slow = edge.copy()
        for ch in speeds:
            slow |= rec.data[ch] < W_MIN
        bad = binary_dilation(slow, np.ones(2 * n + 1, dtype=bool))
        return ~bad[:-n:n] & (over(np.cumsum(bad)) == 0)

    values: dict[str, tuple[float, float]] = {}
    used = np.zeros(over(rec.t).size, dtype=bool)
    ok = usable("omega_p", "omega_1")
    if np.count_nonzero(ok) >= 20:
        y = over(integral(-c * ratio * T - dr.b_1 * w_p * np.abs(w_p)))[ok]
        X = np.column_stack([over(d["omega_p"]), over(d["omega_1"])])[ok]
        coef, se = _lstsq(X, y)
        values["J_p"], values["J_1"] = (float(coef[0]), float(se[0])), (float(coef[1]), float(se[1]))
        # for runs that do not excite J_1 (together): J_p with J_1 held at the prior's
        coef, se = _lstsq(X[:, :1], y - dr.J_1 * X[:, 1])
        values[J_P_HELD] = (float(coef[0]), float(se[0]))
        used |= ok
    if "omega_s" in d and np.count_nonzero(ok := usable("omega_s")) >= 20:
        w_s = d["omega_s"]
        y = over(integral(T - dr.b_2 * w_s * np.abs(w_s)))[ok]
        # J_s dw_s = (T - T_b) dt: regress the (noisier) speed change on the torque's integral
        coef, se = _lstsq(np.column_stack([y, np.full(y.size, n * rec.dt)]), over(w_s)[ok])
        if coef[0] > 0.0:
            values["J_s"] = (float(1.0 / coef[0]), float(se[0] / coef[0] ** 2))
        used |= ok
    if not values:
        return None
    t_used = rec.t[:-n:n][used]
    return InertiaFit(rec, values, float(t_used[0]), float(t_used[-1] + n * rec.dt))


def excited(value: float, se: float) -> bool:
    """Whether the data determine an inertia: positive, with a standard error below :data:`REL_SE_MAX` of it."""
    return value > 0.0 and se < REL_SE_MAX * value
